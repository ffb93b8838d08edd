#include "robotperf/rmw/transport.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <sys/file.h>
#include <time.h>
#include <unistd.h>

#include <cctype>
#include <charconv>
#include <chrono>
#include <cstdlib>
#include <random>
#include <stdexcept>
#include <thread>

#include "cyclonedds_transport.hpp"
#include "fastdds_transport.hpp"
#include "intra_transport.hpp"

namespace robotperf::rmw {

QoS QoS::from_profile_name(const std::string& name) {
  if (name == "default") return ros_default();
  if (name == "sensor_data") return sensor_data();
  throw std::invalid_argument("unknown QoS profile '" + name + "' (choose default or sensor_data)");
}

std::string qos_incompatibility(const QoS& offered, const QoS& requested) {
  if (requested.reliability == Reliability::kReliable &&
      offered.reliability == Reliability::kBestEffort) {
    return "a reliable subscription needs a reliable publisher";
  }
  if (requested.durability == Durability::kTransientLocal &&
      offered.durability == Durability::kVolatile) {
    return "a transient_local subscription needs a transient_local publisher";
  }
  return {};
}

std::string to_string(Reliability reliability) {
  return reliability == Reliability::kReliable ? "reliable" : "best_effort";
}

std::string to_string(Durability durability) {
  return durability == Durability::kTransientLocal ? "transient_local" : "volatile";
}

std::string to_string(const QoS& qos) {
  return to_string(qos.reliability) + ", " + to_string(qos.durability) + ", " +
         (qos.history == History::kKeepLast ? "keep_last " + std::to_string(qos.depth)
                                            : std::string("keep_all"));
}

RosDistro ros_distro_from_name(const std::string& name) {
  if (name == "humble") return RosDistro::kHumble;
  if (name == "iron") return RosDistro::kIron;
  if (name == "jazzy") return RosDistro::kJazzy;
  throw std::invalid_argument("unknown ROS 2 distribution '" + name +
                              "' (choose humble, iron or jazzy; later ones follow jazzy)");
}

std::string to_string(RosDistro distro) {
  switch (distro) {
    case RosDistro::kHumble:
      return "humble";
    case RosDistro::kIron:
      return "iron";
    case RosDistro::kJazzy:
      return "jazzy";
  }
  return "?";
}

std::unique_ptr<Transport> make_transport(const std::string& name,
                                          const TransportOptions& options) {
  if (name == "intra") return make_intra_transport();
  if (name == "fastdds") return make_fastdds_transport(options);
  if (name == "cyclonedds") return make_cyclonedds_transport(options);
  throw std::invalid_argument("unknown transport '" + name +
                              "' (choose intra, fastdds or cyclonedds)");
}

std::string to_hex(const ParticipantId& id) {
  static constexpr char kDigits[] = "0123456789abcdef";
  std::string out;
  for (uint8_t b : id) {
    out += kDigits[b >> 4];
    out += kDigits[b & 15];
  }
  return out;
}

std::string user_data_value(std::string_view user_data, std::string_view key) {
  std::size_t at = 0;
  while (at < user_data.size()) {
    const std::size_t end = std::min(user_data.find(';', at), user_data.size());
    const std::string_view pair = user_data.substr(at, end - at);
    if (pair.size() > key.size() && pair.starts_with(key) && pair[key.size()] == '=') {
      return std::string(pair.substr(key.size() + 1));
    }
    at = end + 1;
  }
  return {};
}

std::string to_text(const Gid& gid) {
  static constexpr char kDigits[] = "0123456789abcdef";
  std::string out;
  for (uint8_t b : gid) {
    if (!out.empty()) out += '.';
    out += kDigits[b >> 4];
    out += kDigits[b & 15];
  }
  return out;
}

std::optional<int> parse_domain_id(std::string_view text) {
  unsigned id = 0;
  const char* end = text.data() + text.size();
  const auto [stop, error] = std::from_chars(text.data(), end, id);
  if (error != std::errc() || stop != end || id > static_cast<unsigned>(kMaxDomainId))
    return std::nullopt;
  return static_cast<int>(id);
}

int domain_id_from_environment() {
  const char* value = std::getenv("ROS_DOMAIN_ID");
  if (value == nullptr || *value == '\0') return 0;
  const std::optional<int> id = parse_domain_id(value);
  if (!id) {
    throw std::invalid_argument(std::string("ROS_DOMAIN_ID='") + value +
                                "' is not a domain id between 0 and " +
                                std::to_string(kMaxDomainId));
  }
  return *id;
}

std::vector<std::string> static_peers_from_environment() {
  const char* value = std::getenv("ROS_STATIC_PEERS");
  std::vector<std::string> peers;
  if (value == nullptr) return peers;
  std::string_view rest = value;
  while (!rest.empty()) {
    const auto semicolon = rest.find(';');
    const std::string peer(rest.substr(0, semicolon));
    rest = semicolon == std::string_view::npos ? std::string_view{} : rest.substr(semicolon + 1);
    if (peer.empty()) continue;
    in_addr address{};
    if (inet_pton(AF_INET, peer.c_str(), &address) != 1) {
      throw std::invalid_argument("ROS_STATIC_PEERS: '" + peer +
                                  "' is not an IPv4 address (expected e.g. 10.0.0.2;10.0.0.3)");
    }
    peers.push_back(peer);
  }
  return peers;
}

namespace {

// A lock on /tmp/robotperf-domain-<N>.lock, held while the descriptor is open; -1 when another
// process holds it, or the file cannot be made or is a link (planted by another user: a lock must
// not create or open the file it points at). The kernel drops it when the process ends.
int lock_domain(int domain) {
  const std::string path = "/tmp/robotperf-domain-" + std::to_string(domain) + ".lock";
  // Read-only: any user may lock a file another user created.
  const int fd = open(path.c_str(), O_RDONLY | O_CREAT | O_NOFOLLOW | O_CLOEXEC, 0666);
  if (fd < 0) return -1;
  if (flock(fd, LOCK_EX | LOCK_NB) != 0) {
    close(fd);
    return -1;
  }
  return fd;
}

}  // namespace

int reserved_domain() {
  static const int domain = [] {
    const int start = static_cast<int>(getpid() % kLastSecuredDomain);
    for (int i = 0; i < kLastSecuredDomain; ++i) {
      const int candidate = 1 + (start + i) % kLastSecuredDomain;
      if (lock_domain(candidate) >= 0) return candidate;  // held until this process ends
    }
    throw TransportError("no DDS domain left to reserve: " + std::to_string(kLastSecuredDomain) +
                         " robotperf processes hold one each");
  }();
  return domain;
}

int find_quiet_domain(const std::string& transport, double listen_s) {
  if (transport == "intra") return 0;
  constexpr int kTries = 16;
  std::random_device entropy;
  std::uniform_int_distribution<int> domain(1, kLastSecuredDomain);
  for (int t = 0; t < kTries; ++t) {
    const int candidate = domain(entropy);
    const int lock = lock_domain(candidate);
    if (lock < 0) continue;  // another robotperf process is on it, or looking at it
    TransportOptions options;
    options.domain_id = candidate;
    const auto probe = make_transport(transport, options);
    // Participants answer a newcomer's first announcements, usually within milliseconds, and
    // announce themselves periodically (Fast DDS: every 3 s), which bounds the wait.
    const int64_t end = steady_now_ns() + static_cast<int64_t>(listen_s * 1e9);
    bool quiet = true;
    while (quiet && steady_now_ns() < end) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
      quiet = probe->peers().empty();
    }
    if (quiet) return candidate;  // the lock stays held until this process ends
    close(lock);
  }
  throw TransportError("--domain auto: " + std::to_string(kTries) +
                       " domains tried, all have participants; give a --domain");
}

int64_t steady_now_ns() {
  timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return int64_t{ts.tv_sec} * 1'000'000'000 + ts.tv_nsec;
}

int64_t wall_now_ns() {
  timespec ts;
  clock_gettime(CLOCK_REALTIME, &ts);
  return int64_t{ts.tv_sec} * 1'000'000'000 + ts.tv_nsec;
}

std::string dds_topic_name(const std::string& ros_topic) {
  auto bad = [&](const char* why) {
    return std::invalid_argument("invalid topic name '" + ros_topic + "': " + why);
  };
  if (ros_topic.empty() || ros_topic[0] != '/') throw bad("must be absolute (start with '/')");
  if (ros_topic.size() > 1 && ros_topic.back() == '/') throw bad("must not end with '/'");
  char prev = 0;
  for (char c : ros_topic) {
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '/')) {
      throw bad("only letters, digits, '_' and '/' are allowed");
    }
    if (c == '/' && prev == '/') throw bad("must not contain '//'");
    if (std::isdigit(static_cast<unsigned char>(c)) && prev == '/') {
      throw bad("a name token must not start with a digit");
    }
    prev = c;
  }
  return "rt" + ros_topic;
}

NodeName parse_node_name(std::string_view full_name) {
  const std::string quoted = "node name '" + std::string(full_name) + "'";
  auto check_token = [&](std::string_view token, const char* what) {
    if (token.empty()) {
      throw std::invalid_argument(quoted + " is not a ROS 2 node name: its " + what +
                                  " has an empty part ('//', or a '/' at an end)");
    }
    if (token.front() >= '0' && token.front() <= '9') {
      throw std::invalid_argument(quoted + " is not a ROS 2 node name: its " + what +
                                  " starts with a digit ('" + std::string(token) + "')");
    }
    for (const char ch : token) {
      const bool ok = (ch >= 'a' && ch <= 'z') || (ch >= 'A' && ch <= 'Z') ||
                      (ch >= '0' && ch <= '9') || ch == '_';
      if (!ok) {
        throw std::invalid_argument(quoted + " is not a ROS 2 node name: '" + std::string(1, ch) +
                                    "' in its " + what +
                                    " (letters, digits and '_' only; a namespace before it: "
                                    "'ns/relay')");
      }
    }
  };
  if (full_name.empty()) throw std::invalid_argument("a node needs a name");
  std::string_view rest = full_name;
  if (rest.front() == '/') rest.remove_prefix(1);
  const std::size_t slash = rest.rfind('/');
  NodeName out;
  out.name = std::string(slash == std::string_view::npos ? rest : rest.substr(slash + 1));
  check_token(out.name, "name");
  if (out.name.size() > 255)
    throw std::invalid_argument(quoted + " is not a ROS 2 node name: longer than 255 characters");
  if (slash != std::string_view::npos) {
    const std::string_view ns = rest.substr(0, slash);
    std::size_t start = 0;
    while (start <= ns.size()) {
      const std::size_t end = std::min(ns.find('/', start), ns.size());
      check_token(ns.substr(start, end - start), "namespace");
      start = end + 1;
    }
    out.namespace_ = "/" + std::string(ns);
  }
  return out;
}

}  // namespace robotperf::rmw
