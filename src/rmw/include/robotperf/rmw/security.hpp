// DDS Security (SROS2-style): the keystore robotperf creates and reads, and what a secured
// participant of the DDS transports needs from it.
//
// A keystore holds one certificate authority and, per enclave, the six files a participant
// presents: its identity (certificate and private key, signed by the identity CA) and its access
// rights (governance and permissions, signed by the permissions CA). The layout is the one
// `ros2 security create_keystore` and `create_enclave` make, so that a ROS 2 node can use the
// same keystore (ROS_SECURITY_KEYSTORE, ROS_SECURITY_ENCLAVE_OVERRIDE) and talk to robotperf.
#pragma once

#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

namespace robotperf::rmw {

// A keystore that is missing, incomplete or cannot be written; the message is one line.
class SecurityError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The files of one enclave of a keystore: the built-in plug-ins' inputs (PKI-DH authentication,
// Access-Permissions access control), absolute paths.
struct SecurityFiles {
  std::filesystem::path identity_ca;     // identity_ca.cert.pem
  std::filesystem::path certificate;     // cert.pem: the participant's identity
  std::filesystem::path private_key;     // key.pem
  std::filesystem::path permissions_ca;  // permissions_ca.cert.pem
  std::filesystem::path governance;      // governance.p7s: the domain's rules, signed
  std::filesystem::path permissions;     // permissions.p7s: this enclave's rights, signed
  std::string enclave;                   // e.g. "/robotperf"

  friend bool operator==(const SecurityFiles&, const SecurityFiles&) = default;
};

inline constexpr const char* kDefaultEnclave = "/robotperf";

// The highest DDS domain a keystore's governance and permissions can name (DDS Security's XML
// schemas stop at 230); secured participants run on domains 0 to 230.
inline constexpr int kLastSecuredDomain = 230;

// The files of `enclave` in `keystore` (<keystore>/enclaves/<enclave without its leading />/).
// Throws SecurityError when the keystore is not a folder, a file is missing or the enclave name
// is invalid.
SecurityFiles enclave_files(const std::filesystem::path& keystore,
                            const std::string& enclave = kDefaultEnclave);

// Creates a keystore in `dir` (which must not exist or be empty) with `enclaves` (names like
// "/robotperf" or "/robot/camera": segments of letters, digits and '_'): one self-signed ECDSA
// P-256 CA as identity and permissions CA, the governance of SROS2's default (authenticated
// participants only; discovery, liveliness and data encrypted, RTPS messages signed) and per
// enclave a certificate valid `validity_days`, its key and permissions to publish and subscribe
// every topic on domains 0 to 230. Where `dir` already holds a keystore, adds the enclaves it
// lacks, signed by its CA; refuses when it lacks none. Throws SecurityError; on error nothing is
// left half written.
void create_keystore(const std::filesystem::path& dir, const std::vector<std::string>& enclaves,
                     int validity_days = 3650);

// Replaces the keystore in `dir` (a damaged one too: a file missing, altered or signed by a CA
// that no longer matches) with a new one: a new CA, and every enclave it held plus `enclaves`
// (/robotperf when that makes none). The new keystore takes the old one's place in one rename;
// on error the old one stays. Refuses a folder that is not a keystore. Returns the enclaves made.
std::vector<std::string> renew_keystore(const std::filesystem::path& dir,
                                        std::vector<std::string> enclaves,
                                        int validity_days = 3650);

// One line for results: which plug-ins a participant with `files` runs and what its governance
// protects, e.g. "authentication PKI-DH, access control (governance: rtps SIGN, discovery
// ENCRYPT, data ENCRYPT), crypto AES-GCM-GMAC, enclave /robotperf".
std::string describe(const SecurityFiles& files);

}  // namespace robotperf::rmw
