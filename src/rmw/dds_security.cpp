// The DDS Security keystore: reading an enclave's files, and creating a keystore with OpenSSL's
// libcrypto (the library both DDS implementations verify it with).
#include <fcntl.h>
#include <openssl/bio.h>
#include <openssl/bn.h>
#include <openssl/err.h>
#include <openssl/evp.h>
#include <openssl/pem.h>
#include <openssl/pkcs7.h>
#include <openssl/x509.h>
#include <openssl/x509v3.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <string_view>
#include <system_error>
#include <utility>
#include <vector>

#include "robotperf/rmw/security.hpp"

namespace robotperf::rmw {
namespace {

namespace fs = std::filesystem;

// The DDS domains the governance and the permissions cover: all that the DDS Security schemas
// allow (Cyclone DDS refuses a document naming 231 or 232, though RTPS ports would fit them).
constexpr int kFirstDomain = 0;
constexpr int kLastDomain = kLastSecuredDomain;

// Names of an enclave's files, as SROS2 lays them out.
constexpr const char* kIdentityCa = "identity_ca.cert.pem";
constexpr const char* kCertificate = "cert.pem";
constexpr const char* kPrivateKey = "key.pem";
constexpr const char* kPermissionsCa = "permissions_ca.cert.pem";
constexpr const char* kGovernance = "governance.p7s";
constexpr const char* kPermissions = "permissions.p7s";

// --- Enclave names and folders -------------------------------------------------------------------

// "/robotperf", "/robot/camera_1": absolute, segments of letters, digits and '_'.
void check_enclave_name(const std::string& enclave) {
  auto bad = [&](const char* why) {
    return SecurityError("invalid enclave name '" + enclave + "': " + why);
  };
  if (enclave.size() < 2 || enclave[0] != '/') throw bad("must start with '/' and name something");
  if (enclave.back() == '/') throw bad("must not end with '/'");
  char prev = 0;
  for (char c : enclave) {
    const bool word =
        (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_';
    if (!word && c != '/') throw bad("only letters, digits, '_' and '/' are allowed");
    if (c == '/' && prev == '/') throw bad("must not contain '//'");
    prev = c;
  }
}

fs::path enclave_folder(const fs::path& keystore, const std::string& enclave) {
  return keystore / "enclaves" / enclave.substr(1);
}

// The keystore folder as one absolute path without a trailing '/', so that it has a parent to
// build next to and a name.
fs::path keystore_path(const fs::path& dir) {
  fs::path path = fs::absolute(dir).lexically_normal();
  if (!path.has_filename() && path.has_parent_path()) path = path.parent_path();
  return path;
}

// --- OpenSSL objects -----------------------------------------------------------------------------

template <auto Free>
struct Freer {
  template <class T>
  void operator()(T* p) const {
    Free(p);
  }
};
using Key = std::unique_ptr<EVP_PKEY, Freer<EVP_PKEY_free>>;
using Certificate = std::unique_ptr<X509, Freer<X509_free>>;
using Bio = std::unique_ptr<BIO, Freer<BIO_free_all>>;
using Pkcs7 = std::unique_ptr<PKCS7, Freer<PKCS7_free>>;
using BigNum = std::unique_ptr<BIGNUM, Freer<BN_free>>;
using Extension = std::unique_ptr<X509_EXTENSION, Freer<X509_EXTENSION_free>>;

// A SecurityError for a failed OpenSSL call, with OpenSSL's latest reason; clears its queue.
SecurityError openssl_error(const std::string& what) {
  std::string reason;
  if (const unsigned long code = ERR_peek_last_error(); code != 0) {
    std::array<char, 256> text{};
    ERR_error_string_n(code, text.data(), text.size());
    reason = std::string(": ") + text.data();
  }
  ERR_clear_error();
  return SecurityError("keystore: " + what + " failed" + reason);
}

Bio memory_bio() {
  Bio bio(BIO_new(BIO_s_mem()));
  if (!bio) throw openssl_error("BIO_new");
  return bio;
}

// A read-only BIO over `bytes`, which must outlive it.
Bio memory_bio(const std::string& bytes) {
  Bio bio(BIO_new_mem_buf(bytes.data(), static_cast<int>(bytes.size())));
  if (!bio) throw openssl_error("BIO_new_mem_buf");
  return bio;
}

std::string bio_text(BIO* bio) {
  char* data = nullptr;
  const long size = BIO_get_mem_data(bio, &data);
  return size > 0 ? std::string(data, static_cast<std::size_t>(size)) : std::string();
}

// ECDSA on P-256 with SHA-256: the one key type both DDS implementations' PKI-DH accepts besides
// RSA-2048, and the one SROS2 uses.
Key new_key() {
  Key key(EVP_EC_gen("P-256"));
  if (!key) throw openssl_error("generating a P-256 key");
  return key;
}

std::string key_pem(EVP_PKEY* key) {
  Bio bio = memory_bio();
  // Unencrypted PKCS#8: DDS reads it without a password.
  if (PEM_write_bio_PrivateKey(bio.get(), key, nullptr, nullptr, 0, nullptr, nullptr) != 1) {
    throw openssl_error("writing a private key");
  }
  return bio_text(bio.get());
}

std::string certificate_pem(X509* cert) {
  Bio bio = memory_bio();
  if (PEM_write_bio_X509(bio.get(), cert) != 1) throw openssl_error("writing a certificate");
  return bio_text(bio.get());
}

// The certificate's subject as DDS compares it with a grant's subject_name (RFC 2253 form:
// "CN=/robotperf").
std::string subject_of(X509* cert) {
  Bio bio = memory_bio();
  if (X509_NAME_print_ex(bio.get(), X509_get_subject_name(cert), 0, XN_FLAG_RFC2253) < 0) {
    throw openssl_error("printing a certificate subject");
  }
  return bio_text(bio.get());
}

// What a certificate is for.
struct CertificateRequest {
  std::string common_name;
  EVP_PKEY* key = nullptr;         // its public key's pair
  X509* issuer = nullptr;          // null: self-signed
  EVP_PKEY* issuer_key = nullptr;  // null: self-signed
  // Valid from a day before it is issued, as SROS2's certificates are (a host whose clock lags
  // accepts it), to validity_days after.
  std::time_t issued = 0;
  int validity_days = 0;
};

constexpr std::time_t kDay = 24 * 60 * 60;

Certificate new_certificate(const CertificateRequest& request) {
  const bool is_ca = request.issuer == nullptr;
  Certificate cert(X509_new());
  if (!cert) throw openssl_error("X509_new");
  // A random 159-bit serial, as RFC 5280 asks for (positive, at most 20 bytes).
  BigNum serial(BN_new());
  if (!serial || BN_rand(serial.get(), 159, BN_RAND_TOP_ANY, BN_RAND_BOTTOM_ANY) != 1 ||
      BN_to_ASN1_INTEGER(serial.get(), X509_get_serialNumber(cert.get())) == nullptr) {
    throw openssl_error("making a serial number");
  }
  std::time_t issued = request.issued;
  X509_NAME* subject = X509_get_subject_name(cert.get());
  if (X509_set_version(cert.get(), X509_VERSION_3) != 1 ||
      X509_time_adj_ex(X509_getm_notBefore(cert.get()), -1, 0, &issued) == nullptr ||
      X509_time_adj_ex(X509_getm_notAfter(cert.get()), request.validity_days, 0, &issued) ==
          nullptr ||
      X509_set_pubkey(cert.get(), request.key) != 1 ||
      X509_NAME_add_entry_by_txt(
          subject, "CN", MBSTRING_UTF8,
          reinterpret_cast<const unsigned char*>(request.common_name.c_str()), -1, -1, 0) != 1 ||
      X509_set_issuer_name(cert.get(), is_ca ? subject : X509_get_subject_name(request.issuer)) !=
          1) {
    throw openssl_error("filling in a certificate");
  }
  // The CA signs certificates and the governance and permissions documents (S/MIME, which asks
  // for digitalSignature); an identity only signs DDS's authentication handshake.
  const std::vector<std::pair<int, const char*>> extensions =
      is_ca ? std::vector<std::pair<int, const char*>>{{NID_basic_constraints, "critical,CA:TRUE"},
                                                       {NID_key_usage,
                                                        "critical,keyCertSign,cRLSign,"
                                                        "digitalSignature"},
                                                       {NID_subject_key_identifier, "hash"},
                                                       {NID_authority_key_identifier, "keyid"}}
            : std::vector<std::pair<int, const char*>>{{NID_basic_constraints, "critical,CA:FALSE"},
                                                       {NID_key_usage, "critical,digitalSignature"},
                                                       {NID_subject_key_identifier, "hash"},
                                                       {NID_authority_key_identifier, "keyid"}};
  X509V3_CTX context;
  X509V3_set_ctx_nodb(&context);
  X509V3_set_ctx(&context, is_ca ? cert.get() : request.issuer, cert.get(), nullptr, nullptr, 0);
  for (const auto& [nid, value] : extensions) {
    Extension extension(X509V3_EXT_conf_nid(nullptr, &context, nid, value));
    if (!extension || X509_add_ext(cert.get(), extension.get(), -1) != 1) {
      throw openssl_error(std::string("adding certificate extension ") + OBJ_nid2sn(nid));
    }
  }
  EVP_PKEY* signer = is_ca ? request.key : request.issuer_key;
  if (X509_sign(cert.get(), signer, EVP_sha256()) == 0)
    throw openssl_error("signing a certificate");
  return cert;
}

// `document` signed by the CA as S/MIME (PKCS#7, detached signature, text): what both DDS
// implementations read with SMIME_read_PKCS7 and check with PKCS7_verify.
std::string sign(const std::string& document, X509* ca, EVP_PKEY* ca_key) {
  constexpr int kFlags = PKCS7_DETACHED | PKCS7_TEXT;
  Bio to_sign = memory_bio(document);
  Pkcs7 signature(PKCS7_sign(ca, ca_key, nullptr, to_sign.get(), kFlags));
  if (!signature) throw openssl_error("signing a document");
  // The signing consumed its input: the message carries the document again, in clear.
  Bio content = memory_bio(document);
  Bio out = memory_bio();
  if (SMIME_write_PKCS7(out.get(), signature.get(), content.get(), kFlags) != 1) {
    throw openssl_error("writing an S/MIME document");
  }
  return bio_text(out.get());
}

// --- Documents -----------------------------------------------------------------------------------

std::string domain_range() {
  return "<domains><id_range><min>" + std::to_string(kFirstDomain) + "</min><max>" +
         std::to_string(kLastDomain) + "</max></id_range></domains>";
}

// SROS2's default governance: only authenticated participants with permissions join; discovery,
// liveliness, and every topic's data and metadata are encrypted; whole RTPS messages are signed.
std::string governance_xml() {
  return R"(<?xml version="1.0" encoding="UTF-8"?>
<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance" xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-SECURITY/20170901/omg_shared_ca_governance.xsd">
  <domain_access_rules>
    <domain_rule>
      )" +
         domain_range() +
         R"(
      <allow_unauthenticated_participants>false</allow_unauthenticated_participants>
      <enable_join_access_control>true</enable_join_access_control>
      <discovery_protection_kind>ENCRYPT</discovery_protection_kind>
      <liveliness_protection_kind>ENCRYPT</liveliness_protection_kind>
      <rtps_protection_kind>SIGN</rtps_protection_kind>
      <topic_access_rules>
        <topic_rule>
          <topic_expression>*</topic_expression>
          <enable_discovery_protection>true</enable_discovery_protection>
          <enable_liveliness_protection>true</enable_liveliness_protection>
          <enable_read_access_control>true</enable_read_access_control>
          <enable_write_access_control>true</enable_write_access_control>
          <metadata_protection_kind>ENCRYPT</metadata_protection_kind>
          <data_protection_kind>ENCRYPT</data_protection_kind>
        </topic_rule>
      </topic_access_rules>
    </domain_rule>
  </domain_access_rules>
</dds>
)";
}

// "2025-01-31T12:00:00", UTC.
std::string xml_time(std::time_t t) {
  std::tm utc{};
  gmtime_r(&t, &utc);
  std::array<char, 32> text{};
  std::strftime(text.data(), text.size(), "%Y-%m-%dT%H:%M:%S", &utc);
  return text.data();
}

// The enclave may publish and subscribe every topic of every domain the governance covers.
std::string permissions_xml(const std::string& enclave, const std::string& subject,
                            std::time_t not_before, std::time_t not_after) {
  return R"(<?xml version="1.0" encoding="UTF-8"?>
<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance" xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-SECURITY/20170901/omg_shared_ca_permissions.xsd">
  <permissions>
    <grant name=")" +
         enclave + R"(">
      <subject_name>)" +
         subject + R"(</subject_name>
      <validity>
        <not_before>)" +
         xml_time(not_before) + R"(</not_before>
        <not_after>)" +
         xml_time(not_after) + R"(</not_after>
      </validity>
      <allow_rule>
        )" +
         domain_range() +
         R"(
        <publish><topics><topic>*</topic></topics></publish>
        <subscribe><topics><topic>*</topic></topics></subscribe>
      </allow_rule>
      <default>DENY</default>
    </grant>
  </permissions>
</dds>
)";
}

// --- Files ---------------------------------------------------------------------------------------

SecurityError file_error(const std::string& what, const fs::path& path, int error) {
  return SecurityError("keystore: cannot " + what + " " + path.string() + ": " +
                       std::strerror(error));
}

// A new file holding `bytes`, with exactly `mode` (whatever the umask).
void write_file(const fs::path& path, const std::string& bytes, mode_t mode = 0644) {
  const int fd = open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, mode);
  if (fd < 0) throw file_error("create", path, errno);
  std::size_t written = 0;
  int error = fchmod(fd, mode) == 0 ? 0 : errno;
  while (error == 0 && written < bytes.size()) {
    const ssize_t n = write(fd, bytes.data() + written, bytes.size() - written);
    if (n < 0 && errno != EINTR) error = errno;
    if (n > 0) written += static_cast<std::size_t>(n);
  }
  // On disk before it is renamed into the keystore: the CA's key cannot be made again.
  if (error == 0 && fsync(fd) != 0) error = errno;
  if (close(fd) != 0 && error == 0) error = errno;
  if (error != 0) throw file_error("write", path, error);
}

// Flushes a folder's entries to disk (the files renamed into it, the folders made in it).
void sync_folder(const fs::path& path) {
  const int fd = open(path.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) throw file_error("open", path, errno);
  const int error = fsync(fd) == 0 ? 0 : errno;
  close(fd);
  if (error != 0) throw file_error("sync", path, error);
}

// sync_folder of `root` and every folder in it.
void sync_folders(const fs::path& root) {
  std::error_code error;
  for (auto it = fs::recursive_directory_iterator(root, error);
       !error && it != fs::recursive_directory_iterator(); it.increment(error)) {
    if (it->is_directory(error) && !it->is_symlink(error)) sync_folder(it->path());
  }
  if (error) throw SecurityError("keystore: cannot list " + root.string() + ": " + error.message());
  sync_folder(root);
}

std::string read_file(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream bytes;
  bytes << in.rdbuf();
  if (!in) throw SecurityError("keystore: cannot read " + path.string());
  return bytes.str();
}

// The PEM certificate or private key in `path`; null when it holds none.
Certificate read_certificate(const fs::path& path) {
  const std::string text = read_file(path);  // outlives the BIO over it
  Bio in = memory_bio(text);
  return Certificate(PEM_read_bio_X509(in.get(), nullptr, nullptr, nullptr));
}

Key read_private_key(const fs::path& path) {
  const std::string text = read_file(path);
  Bio in = memory_bio(text);
  return Key(PEM_read_bio_PrivateKey(in.get(), nullptr, nullptr, nullptr));
}

constexpr fs::perms kPublicFolder = fs::perms::owner_all | fs::perms::group_read |
                                    fs::perms::group_exec | fs::perms::others_read |
                                    fs::perms::others_exec;

// `path` and its missing parents; `perms` (whatever the umask) for `path` if it is new.
void make_folder(const fs::path& path, fs::perms perms = kPublicFolder) {
  std::error_code error;
  if (fs::create_directories(path, error)) fs::permissions(path, perms, error);
  if (error)
    throw SecurityError("keystore: cannot create " + path.string() + ": " + error.message());
}

void set_permissions(const fs::path& path, fs::perms perms) {
  std::error_code error;
  fs::permissions(path, perms, error);
  if (error)
    throw SecurityError("keystore: cannot chmod " + path.string() + ": " + error.message());
}

// A temporary folder that is removed with everything in it unless kept.
class ScratchFolder {
 public:
  // A new folder named after `name` with a random suffix, in `parent`.
  ScratchFolder(const fs::path& parent, const std::string& name) {
    std::string pattern = (parent / (name + "-XXXXXX")).string();
    if (mkdtemp(pattern.data()) == nullptr) throw file_error("create a folder in", parent, errno);
    path_ = pattern;
  }
  ScratchFolder(const ScratchFolder&) = delete;
  ScratchFolder& operator=(const ScratchFolder&) = delete;
  ~ScratchFolder() {
    std::error_code ignored;
    if (!path_.empty()) fs::remove_all(path_, ignored);
  }
  const fs::path& path() const { return path_; }
  // It was moved into its place: nothing to remove.
  void keep() { path_.clear(); }

 private:
  fs::path path_;
};

void move(const fs::path& from, const fs::path& to) {
  std::error_code error;
  fs::rename(from, to, error);
  if (error) {
    throw SecurityError("keystore: cannot move " + from.string() + " to " + to.string() + ": " +
                        error.message());
  }
}

void link(const fs::path& to, const fs::path& path) {
  std::error_code error;
  fs::create_symlink(to, path, error);
  if (error)
    throw SecurityError("keystore: cannot create " + path.string() + ": " + error.message());
}

// --- The keystore --------------------------------------------------------------------------------

// The enclaves a keystore holds: every folder under enclaves/ with a certificate or a key, named
// as an enclave ("/robot/camera"). Whatever else is there (a damaged enclave's remains without
// either) is not one.
std::vector<std::string> enclaves_in(const fs::path& keystore) {
  std::vector<std::string> found;
  std::error_code error;
  const fs::path root = keystore / "enclaves";
  for (fs::recursive_directory_iterator it(root, error), end; !error && it != end;
       it.increment(error)) {
    if (!it->is_directory(error)) continue;
    if (!fs::exists(it->path() / kCertificate, error) &&
        !fs::exists(it->path() / kPrivateKey, error))
      continue;
    const std::string name = "/" + it->path().lexically_relative(root).generic_string();
    try {
      check_enclave_name(name);
      found.push_back(name);
    } catch (const SecurityError&) {
      // Not a name robotperf would have made: not an enclave of ours.
    }
  }
  std::ranges::sort(found);
  return found;
}

// The CA of a keystore (identity and permissions CA at once) and its signed governance.
struct Authority {
  Certificate certificate;
  Key key;
  std::string certificate_pem;
  std::string governance_p7s;
};

fs::path ca_certificate_path(const fs::path& keystore) {
  return keystore / "public" / "ca.cert.pem";
}
fs::path ca_key_path(const fs::path& keystore) {
  return keystore / "private" / "ca.key.pem";
}
fs::path governance_path(const fs::path& keystore) {
  return keystore / "enclaves" / kGovernance;
}

bool holds_keystore(const fs::path& dir) {
  std::error_code ignored;
  return fs::exists(ca_certificate_path(dir), ignored) || fs::exists(ca_key_path(dir), ignored) ||
         fs::exists(governance_path(dir), ignored);
}

Authority new_authority(std::time_t now, int validity_days) {
  Authority ca;
  ca.key = new_key();
  ca.certificate = new_certificate({.common_name = "robotperf keystore CA",
                                    .key = ca.key.get(),
                                    .issued = now,
                                    .validity_days = validity_days});
  ca.certificate_pem = certificate_pem(ca.certificate.get());
  ca.governance_p7s = sign(governance_xml(), ca.certificate.get(), ca.key.get());
  return ca;
}

// The CA of the keystore in `dir`, which must be complete.
Authority load_authority(const fs::path& dir) {
  for (const fs::path& path : {ca_certificate_path(dir), ca_key_path(dir), governance_path(dir)}) {
    std::error_code ignored;
    if (!fs::is_regular_file(path, ignored)) {
      throw SecurityError("keystore " + dir.string() + " is incomplete: " + path.string() +
                          " is missing");
    }
  }
  Authority ca;
  ca.certificate_pem = read_file(ca_certificate_path(dir));
  ca.governance_p7s = read_file(governance_path(dir));
  ca.certificate = read_certificate(ca_certificate_path(dir));
  ca.key = read_private_key(ca_key_path(dir));
  if (!ca.certificate || !ca.key ||
      X509_check_private_key(ca.certificate.get(), ca.key.get()) != 1) {
    throw openssl_error("reading the CA of keystore " + dir.string());
  }
  return ca;
}

// The six files of `enclave`, written into the existing, empty `folder`.
void write_enclave(const fs::path& folder, const std::string& enclave, const Authority& ca,
                   std::time_t now, int validity_days) {
  Key key = new_key();
  Certificate cert = new_certificate({.common_name = enclave,
                                      .key = key.get(),
                                      .issuer = ca.certificate.get(),
                                      .issuer_key = ca.key.get(),
                                      .issued = now,
                                      .validity_days = validity_days});
  // Written in UTC, but Fast DDS reads them as local time (mktime): starting a day early keeps a
  // new keystore valid at once in every time zone.
  const std::string permissions =
      permissions_xml(enclave, subject_of(cert.get()), now - kDay, now + validity_days * kDay);
  write_file(folder / kPrivateKey, key_pem(key.get()), 0600);
  write_file(folder / kCertificate, certificate_pem(cert.get()));
  write_file(folder / kIdentityCa, ca.certificate_pem);
  write_file(folder / kPermissionsCa, ca.certificate_pem);
  write_file(folder / kGovernance, ca.governance_p7s);
  write_file(folder / "permissions.xml", permissions);
  write_file(folder / kPermissions, sign(permissions, ca.certificate.get(), ca.key.get()));
}

// The enclaves of `enclaves` that `keystore` lacks (no certificate), without repeats.
std::vector<std::string> missing_enclaves(const fs::path& keystore,
                                          const std::vector<std::string>& enclaves) {
  std::vector<std::string> missing;
  for (const std::string& enclave : enclaves) {
    std::error_code ignored;
    if (fs::exists(enclave_folder(keystore, enclave) / kCertificate, ignored)) continue;
    if (std::ranges::find(missing, enclave) == missing.end()) missing.push_back(enclave);
  }
  return missing;
}

// A whole keystore in the empty folder `root`: a new CA, its governance and `enclaves`.
void build_keystore(const fs::path& root, const std::vector<std::string>& enclaves,
                    int validity_days) {
  const std::time_t now = std::time(nullptr);
  const Authority ca = new_authority(now, validity_days);
  make_folder(root / "public");
  make_folder(root / "private", fs::perms::owner_all);
  make_folder(root / "enclaves");
  write_file(ca_certificate_path(root), ca.certificate_pem);
  write_file(ca_key_path(root), key_pem(ca.key.get()), 0600);
  // SROS2's tools look for the identity and permissions CA under these names.
  for (const std::string name : {"identity_ca", "permissions_ca"}) {
    link("ca.cert.pem", root / "public" / (name + ".cert.pem"));
    link("ca.key.pem", root / "private" / (name + ".key.pem"));
  }
  write_file(root / "enclaves" / "governance.xml", governance_xml());
  write_file(governance_path(root), ca.governance_p7s);
  for (const std::string& enclave : missing_enclaves(root, enclaves)) {
    make_folder(enclave_folder(root, enclave));
    write_enclave(enclave_folder(root, enclave), enclave, ca, now, validity_days);
  }
  sync_folders(root);
}

std::string joined(const std::vector<std::string>& names) {
  std::string out;
  for (const std::string& name : names) out += (out.empty() ? "" : ", ") + name;
  return out;
}

// Adds the enclaves `keystore` lacks, signed by its CA: all are written into a scratch folder
// first, so that an error leaves the keystore as it was.
void add_enclaves(const fs::path& keystore, const std::vector<std::string>& enclaves,
                  int validity_days) {
  const std::vector<std::string> missing = missing_enclaves(keystore, enclaves);
  if (missing.empty()) {
    throw SecurityError("keystore " + keystore.string() + " already exists" +
                        (enclaves.empty() ? "" : " with enclave(s) " + joined(enclaves)) +
                        "; nothing to add");
  }
  const Authority ca = load_authority(keystore);
  const std::time_t now = std::time(nullptr);
  // In enclaves/, on the keystore's file system; '.' cannot start an enclave name.
  ScratchFolder scratch(keystore / "enclaves", ".new");
  for (std::size_t i = 0; i < missing.size(); ++i) {
    make_folder(scratch.path() / std::to_string(i));
    write_enclave(scratch.path() / std::to_string(i), missing[i], ca, now, validity_days);
  }
  sync_folders(scratch.path());
  // Every place is made ready before anything moves; a move that fails puts the ones before it
  // back.
  for (const std::string& enclave : missing)
    make_folder(enclave_folder(keystore, enclave).parent_path());
  std::vector<std::pair<fs::path, fs::path>> moved;  // from, to
  try {
    for (std::size_t i = 0; i < missing.size(); ++i) {
      const fs::path built = scratch.path() / std::to_string(i);
      const fs::path target = enclave_folder(keystore, missing[i]);
      std::error_code ignored;
      if (!fs::exists(target, ignored)) {
        move(built, target);
        moved.emplace_back(built, target);
      } else {
        // The folder exists as the parent of a nested enclave ("/robot" of "/robot/camera").
        for (const auto& file : fs::directory_iterator(built)) {
          const fs::path to = target / file.path().filename();
          move(file.path(), to);
          moved.emplace_back(file.path(), to);
        }
      }
    }
  } catch (const SecurityError&) {
    for (auto it = moved.rbegin(); it != moved.rend(); ++it) {
      std::error_code ignored;
      fs::rename(it->second, it->first, ignored);
    }
    throw;
  }
  for (const std::string& enclave : missing)
    sync_folder(enclave_folder(keystore, enclave).parent_path());
}

}  // namespace

namespace {

std::string asn1_time_text(const ASN1_TIME* time) {
  Bio out = memory_bio();
  ASN1_TIME_print(out.get(), time);
  return bio_text(out.get());
}

// The enclave's files as the DDS libraries will read them, each named where it fails: the
// certificate and key (PEM, a pair), the certificate issued by the identity CA and valid now, and
// the governance and permissions signed by the permissions CA. The libraries' own errors name
// no file.
void check_enclave_files(const SecurityFiles& files, const std::string& hint) {
  ERR_clear_error();
  auto broken = [&](const fs::path& file, const std::string& why) {
    ERR_clear_error();
    return SecurityError("security keystore file " + file.string() + " " + why + "; " + hint);
  };
  auto certificate = [&](const fs::path& file) {
    Certificate cert = read_certificate(file);
    if (!cert) throw broken(file, "is not a PEM certificate");
    return cert;
  };
  const Certificate cert = certificate(files.certificate);
  const Certificate identity_ca = certificate(files.identity_ca);
  const Certificate permissions_ca = certificate(files.permissions_ca);
  const Key key = read_private_key(files.private_key);
  if (!key) throw broken(files.private_key, "is not a PEM private key");
  if (X509_check_private_key(cert.get(), key.get()) != 1)
    throw broken(files.private_key, "is not the key of " + files.certificate.filename().string());

  auto store_of = [](X509* ca) {
    std::unique_ptr<X509_STORE, Freer<X509_STORE_free>> store(X509_STORE_new());
    if (!store || X509_STORE_add_cert(store.get(), ca) != 1)
      throw openssl_error("making a trust store");
    return store;
  };
  const auto identity = store_of(identity_ca.get());
  std::unique_ptr<X509_STORE_CTX, Freer<X509_STORE_CTX_free>> context(X509_STORE_CTX_new());
  if (!context || X509_STORE_CTX_init(context.get(), identity.get(), cert.get(), nullptr) != 1)
    throw openssl_error("checking a certificate");
  if (X509_verify_cert(context.get()) != 1) {
    const int error = X509_STORE_CTX_get_error(context.get());
    throw broken(files.certificate, std::string("does not check against ") +
                                        files.identity_ca.filename().string() + ": " +
                                        X509_verify_cert_error_string(error) + " (valid from " +
                                        asn1_time_text(X509_get0_notBefore(cert.get())) + " to " +
                                        asn1_time_text(X509_get0_notAfter(cert.get())) + ")");
  }
  const auto permissions = store_of(permissions_ca.get());
  for (const fs::path* document : {&files.governance, &files.permissions}) {
    const std::string text = read_file(*document);
    Bio in = memory_bio(text);
    BIO* detached = nullptr;
    const Pkcs7 signature(SMIME_read_PKCS7(in.get(), &detached));
    const Bio content(detached);
    const Bio out = memory_bio();
    if (!signature || !content ||
        PKCS7_verify(signature.get(), nullptr, permissions.get(), content.get(), out.get(),
                     PKCS7_TEXT) != 1) {
      throw broken(*document,
                   "is not a document signed by " + files.permissions_ca.filename().string());
    }
  }
}

}  // namespace

SecurityFiles enclave_files(const fs::path& keystore, const std::string& enclave) {
  check_enclave_name(enclave);
  const fs::path root = keystore_path(keystore);
  std::error_code ignored;
  if (!fs::is_directory(root, ignored)) {
    throw SecurityError("security keystore " + keystore.string() +
                        " is not a folder; run `robotperf security init " + keystore.string() +
                        "` first");
  }
  const fs::path folder = enclave_folder(root, enclave);
  // An enclave the keystore lacks altogether is added; one whose files are missing or damaged
  // (or signed by a damaged CA) takes a new keystore.
  const std::string hint =
      fs::exists(folder, ignored)
          ? "run `robotperf security init " + keystore.string() +
                " --renew` to replace the keystore's CA and enclaves with new ones"
          : "run `robotperf security init " + keystore.string() + " --enclave " + enclave +
                "` to add it";
  SecurityFiles files{.identity_ca = folder / kIdentityCa,
                      .certificate = folder / kCertificate,
                      .private_key = folder / kPrivateKey,
                      .permissions_ca = folder / kPermissionsCa,
                      .governance = folder / kGovernance,
                      .permissions = folder / kPermissions,
                      .enclave = enclave};
  for (const fs::path* file : {&files.identity_ca, &files.certificate, &files.private_key,
                               &files.permissions_ca, &files.governance, &files.permissions}) {
    if (!fs::is_regular_file(*file, ignored)) {
      throw SecurityError("security keystore " + keystore.string() + " lacks " +
                          file->lexically_relative(root).string() + " (enclave " + enclave + "); " +
                          hint);
    }
  }
  check_enclave_files(files, hint);
  return files;
}

void create_keystore(const fs::path& dir, const std::vector<std::string>& enclaves,
                     int validity_days) {
  ERR_clear_error();
  for (const std::string& enclave : enclaves) check_enclave_name(enclave);
  if (validity_days <= 0) {
    throw SecurityError("keystore: validity must be at least one day, not " +
                        std::to_string(validity_days));
  }
  const fs::path target = keystore_path(dir);
  if (holds_keystore(target)) {
    add_enclaves(target, enclaves, validity_days);
    return;
  }
  std::error_code error;
  if (fs::exists(target, error) &&
      !(fs::is_directory(target, error) && fs::is_empty(target, error))) {
    throw SecurityError("keystore: " + target.string() +
                        " exists and is neither a keystore nor an empty folder");
  }
  // Built next to its place and renamed into it, so that it appears whole or not at all. An
  // existing empty folder is kept (it may be a shell's current folder, which a rename over it
  // would delete): the keystore is built inside it and its three folders renamed into it.
  const bool into_folder = fs::exists(target, error);
  make_folder(target.parent_path());
  ScratchFolder scratch(into_folder ? target : target.parent_path(),
                        into_folder ? ".new" : "." + target.filename().string() + ".new");
  const fs::path& root = scratch.path();
  build_keystore(root, enclaves, validity_days);
  if (into_folder) {
    // public/ last: its CA certificate is what makes a folder a keystore.
    for (const char* part : {"enclaves", "private", "public"}) move(root / part, target / part);
    sync_folder(target);
    return;
  }
  // mkdtemp made it private; the keys are, in private/.
  set_permissions(root, kPublicFolder);
  move(root, target);
  scratch.keep();
  sync_folder(target.parent_path());
}

std::vector<std::string> renew_keystore(const fs::path& dir, std::vector<std::string> enclaves,
                                        int validity_days) {
  ERR_clear_error();
  for (const std::string& enclave : enclaves) check_enclave_name(enclave);
  const fs::path target = keystore_path(dir);
  std::error_code error;
  if (!fs::is_directory(target / "enclaves", error) && !holds_keystore(target)) {
    throw SecurityError("keystore: " + target.string() +
                        " is not a keystore: nothing to renew (robotperf security init " +
                        dir.string() + " makes one)");
  }
  for (const std::string& enclave : enclaves_in(target)) {
    if (std::ranges::find(enclaves, enclave) == enclaves.end()) enclaves.push_back(enclave);
  }
  if (enclaves.empty()) enclaves.push_back(kDefaultEnclave);
  // The new keystore is built beside the old one, then takes its place; the old one is moved
  // aside first and put back if that fails, so that one keystore is always there.
  ScratchFolder fresh(target.parent_path(), "." + target.filename().string() + ".new");
  build_keystore(fresh.path(), enclaves, validity_days);
  set_permissions(fresh.path(), kPublicFolder);
  ScratchFolder old(target.parent_path(), "." + target.filename().string() + ".old");
  move(target, old.path() / "keystore");
  try {
    move(fresh.path(), target);
  } catch (const SecurityError&) {
    fs::rename(old.path() / "keystore", target, error);
    throw;
  }
  fresh.keep();
  sync_folder(target.parent_path());
  return enclaves;
}

std::string describe(const SecurityFiles& files) {
  std::string governance;
  try {
    governance = read_file(files.governance);
  } catch (const SecurityError&) {
  }
  // The first rule's kinds (the signed governance carries its XML in clear).
  auto kind = [&](std::string_view tag) -> std::string {
    const std::string open = "<" + std::string(tag) + ">";
    const auto begin = governance.find(open);
    if (begin == std::string::npos) return "?";
    const auto end = governance.find('<', begin + open.size());
    if (end == std::string::npos) return "?";
    return governance.substr(begin + open.size(), end - begin - open.size());
  };
  return "authentication PKI-DH, access control (governance: rtps " + kind("rtps_protection_kind") +
         ", discovery " + kind("discovery_protection_kind") + ", data " +
         kind("data_protection_kind") + "), crypto AES-GCM-GMAC, enclave " + files.enclave;
}

}  // namespace robotperf::rmw
