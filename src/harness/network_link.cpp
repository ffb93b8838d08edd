#include "robotperf/harness/network_link.hpp"

#include <fcntl.h>
#include <sched.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <sstream>
#include <tuple>

#include "node_processes.hpp"

extern char** environ;

namespace robotperf::harness {
namespace {

namespace fs = std::filesystem;

constexpr const char* kPrefix = "robotperf-";
constexpr const char* kNetnsDir = "/run/netns";
// robotperf-wg-<pid>-XXXXXX: a run's WireGuard keys, in a folder only root reads.
constexpr const char* kKeyFolderPrefix = "robotperf-wg-";
constexpr int kWireguardPort = 51820;
constexpr int kWireguardMtu = 1420;  // wireguard-go's, and wg-quick's over a 1500 path
constexpr int kEthernetMtu = 1500;   // as between two robot computers

struct ToolRun {
  int status = -1;     // exit status; -1 when it could not start
  std::string output;  // stdout and stderr together
};

// Runs a tool (ip, tc) to its end, its stdout and stderr kept.
ToolRun run_tool(const std::vector<std::string>& args) {
  ToolRun out;
  int fds[2];
  if (pipe2(fds, O_CLOEXEC) != 0) {
    out.output = std::string("pipe: ") + std::strerror(errno);
    return out;
  }
  std::vector<std::string> copy = args;
  std::vector<char*> argv;
  for (auto& a : copy) argv.push_back(a.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, fds[1], STDOUT_FILENO);
  posix_spawn_file_actions_adddup2(&actions, fds[1], STDERR_FILENO);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  pid_t pid = -1;
  const int rc = posix_spawnp(&pid, argv[0], &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  close(fds[1]);
  if (rc != 0) {
    close(fds[0]);
    out.output = std::string(std::strerror(rc));
    return out;
  }
  char buf[4096];
  for (ssize_t n; (n = read(fds[0], buf, sizeof buf)) != 0;) {
    if (n < 0) {
      if (errno == EINTR) continue;
      break;
    }
    out.output.append(buf, static_cast<std::size_t>(n));
  }
  close(fds[0]);
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  out.status = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  return out;
}

std::string first_line(const std::string& text) {
  std::string line = text.substr(0, text.find('\n'));
  return line.empty() ? "no message" : line;
}

// Runs a setup step; a failure is one line naming the command and what it printed.
void step(const std::vector<std::string>& args) {
  const ToolRun run = run_tool(args);
  if (run.status == -1) {
    throw NetworkSetupError("--netns: cannot run " + args[0] + " (" + run.output +
                            "); install iproute2 (scripts/install-deps.sh)");
  }
  if (run.status != 0) {
    throw NetworkSetupError("--netns: '" + command_text(args) +
                            "' failed: " + first_line(run.output));
  }
}

std::vector<std::string> split_words(const std::string& text) {
  std::istringstream in(text);
  std::vector<std::string> out;
  for (std::string w; in >> w;) out.push_back(w);
  return out;
}

// The namespaces robotperf made for processes that have ended (a run killed before it could
// remove them), and their key folders.
void remove_stale_namespaces() {
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(kNetnsDir, ec)) {
    const std::string name = entry.path().filename().string();
    if (!name.starts_with(kPrefix)) continue;
    const std::string rest = name.substr(std::strlen(kPrefix));
    const auto dash = rest.find('-');
    if (dash == std::string::npos) continue;
    char* end = nullptr;
    const long pid = std::strtol(rest.c_str(), &end, 10);
    if (end != rest.c_str() + dash || pid <= 0) continue;
    if (kill(static_cast<pid_t>(pid), 0) != 0 && errno == ESRCH) {
      // A killed run's wireguard-go still runs there, and would keep the namespace alive.
      for (const auto& leftover : split_words(run_tool({"ip", "netns", "pids", name}).output)) {
        const long left_pid = std::strtol(leftover.c_str(), nullptr, 10);
        if (left_pid > 0) kill(static_cast<pid_t>(left_pid), SIGTERM);
      }
      run_tool({"ip", "netns", "del", name});
    }
  }
  for (const auto& entry : fs::directory_iterator(fs::temp_directory_path(), ec)) {
    const std::string name = entry.path().filename().string();
    if (!name.starts_with(kKeyFolderPrefix)) continue;
    const long pid = std::strtol(name.c_str() + std::strlen(kKeyFolderPrefix), nullptr, 10);
    if (pid > 0 && kill(static_cast<pid_t>(pid), 0) != 0 && errno == ESRCH)
      fs::remove_all(entry.path(), ec);
  }
}

// tbf's bucket: 100 us at the rate (a link sends no faster than its rate for longer than that),
// at least two full frames. tc's units: bit/kbit/mbit/gbit/tbit, or bps/kbps/... for bytes.
std::string burst_for(const std::string& rate) {
  char* end = nullptr;
  const double value = std::strtod(rate.c_str(), &end);
  const std::string unit = end;
  static const std::vector<std::pair<std::string, double>> kBitsPerUnit = {
      {"bit", 1}, {"kbit", 1e3}, {"mbit", 1e6}, {"gbit", 1e9}, {"tbit", 1e12},
      {"bps", 8}, {"kbps", 8e3}, {"mbps", 8e6}, {"gbps", 8e9}, {"tbps", 8e12}};
  double bits_per_s = 0;
  for (const auto& [name, factor] : kBitsPerUnit) {
    if (unit == name) bits_per_s = value * factor;
  }
  if (!(bits_per_s > 0)) {
    throw NetworkSetupError("--link-rate '" + rate +
                            "': expected a rate as tc writes it (e.g. 100mbit, 1gbit) or none");
  }
  const double bytes = std::max(bits_per_s / 8 * 100e-6, 2.0 * 1514);
  return std::to_string(static_cast<uint64_t>(bytes)) + "b";
}

// Shapes what leaves `device` (in `ns`): netem (delay, jitter, loss) at the root with the rate
// limit under it, or either alone. The tbf queue holds a few large messages' fragments, so that a
// multi-megabyte sample waits instead of being dropped.
void shape(const std::string& ns, const std::string& device, const LinkShaping& shaping) {
  const std::vector<std::string> tc = {"ip",    "netns", "exec", ns,    "tc",
                                       "qdisc", "add",   "dev",  device};
  // Only with a rate: an unshaped link (--link-rate none) has no bucket to size.
  const auto tbf = [&] {
    return std::vector<std::string>{"tbf",   "rate", shaping.rate, "burst", burst_for(shaping.rate),
                                    "limit", "32mb"};
  };
  if (!shaping.netem.empty()) {
    std::vector<std::string> args = tc;
    args.insert(args.end(), {"root", "handle", "1:", "netem"});
    for (auto& w : split_words(shaping.netem)) args.push_back(w);
    if (!shaping.rate.empty()) {
      // netem's own queue must not drop what tbf below it holds.
      args.insert(args.end(), {"limit", "100000"});
    }
    const ToolRun run = run_tool(args);
    if (run.status != 0) {
      if (run.output.find("qdisc kind is unknown") != std::string::npos) {
        throw NetworkSetupError(
            "--netem: this kernel has no netem qdisc (sch_netem); run without --netem, or load "
            "it (modprobe sch_netem) on a kernel that has it");
      }
      throw NetworkSetupError("--netem '" + shaping.netem + "': " + first_line(run.output));
    }
    if (!shaping.rate.empty()) {
      args = tc;
      args.insert(args.end(), {"parent", "1:", "handle", "2:"});
      const auto bucket = tbf();
      args.insert(args.end(), bucket.begin(), bucket.end());
      step(args);
    }
  } else if (!shaping.rate.empty()) {
    std::vector<std::string> args = tc;
    args.push_back("root");
    const auto bucket = tbf();
    args.insert(args.end(), bucket.begin(), bucket.end());
    const ToolRun run = run_tool(args);
    if (run.status != 0)
      throw NetworkSetupError("--link-rate '" + shaping.rate + "': " + first_line(run.output));
  }
}

uint64_t json_u64(const nlohmann::json& j, std::initializer_list<const char*> path) {
  const nlohmann::json* at = &j;
  for (const char* key : path) {
    if (!at->is_object() || !at->contains(key)) return 0;
    at = &(*at)[key];
  }
  return at->is_number_unsigned() ? at->get<uint64_t>() : 0;
}

uint64_t qdisc_drops(const std::string& ns, const std::string& device) {
  const ToolRun run =
      run_tool({"ip", "netns", "exec", ns, "tc", "-s", "-j", "qdisc", "show", "dev", device});
  const auto j = nlohmann::json::parse(run.output, nullptr, false);
  uint64_t drops = 0;
  if (j.is_array()) {
    for (const auto& q : j) drops += json_u64(q, {"drops"});
  }
  return drops;
}

// Writes a WireGuard private key (`wg genkey`) to a file only its owner reads.
fs::path write_private_key(const fs::path& folder, const std::string& name) {
  const ToolRun key = run_tool({"wg", "genkey"});
  if (key.status != 0) throw NetworkSetupError("wg genkey failed: " + first_line(key.output));
  const fs::path path = folder / name;
  const int fd = open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
  const bool written = fd >= 0 && write(fd, key.output.data(), key.output.size()) ==
                                      static_cast<ssize_t>(key.output.size());
  if (fd >= 0) close(fd);
  if (!written)
    throw NetworkSetupError("--netns: cannot write " + path.string() + ": " + std::strerror(errno));
  return path;
}

}  // namespace

std::string to_string(NetworkLayout::Topology topology) {
  return topology == NetworkLayout::Topology::kRouted ? "routed" : "same-subnet";
}

std::string to_string(NetworkLayout::Vpn vpn) {
  return vpn == NetworkLayout::Vpn::kWireguard ? "wireguard" : "none";
}

std::optional<NetworkLayout::Topology> topology_from_name(const std::string& name) {
  if (name == "same-subnet") return NetworkLayout::Topology::kSameSubnet;
  if (name == "routed") return NetworkLayout::Topology::kRouted;
  return std::nullopt;
}

std::optional<NetworkLayout::Vpn> vpn_from_name(const std::string& name) {
  if (name == "none") return NetworkLayout::Vpn::kNone;
  if (name == "wireguard") return NetworkLayout::Vpn::kWireguard;
  return std::nullopt;
}

std::string wireguard_version(const fs::path& tun_device) {
  const ToolRun go = run_tool({"wireguard-go", "--version"});
  if (go.status != 0) {
    throw NetworkSetupError(
        "network: vpn: wireguard needs wireguard-go (this kernel's WireGuard module is not used); "
        "install it (scripts/install-deps.sh)");
  }
  if (run_tool({"wg", "--version"}).status != 0)
    throw NetworkSetupError(
        "network: vpn: wireguard needs wg; install wireguard-tools "
        "(scripts/install-deps.sh)");
  std::error_code ec;
  if (!fs::exists(tun_device, ec)) {
    throw NetworkSetupError("network: vpn: wireguard needs the TUN device " + tun_device.string() +
                            ", which this system lacks (modprobe tun, or a container given it)");
  }
  // "wireguard-go v0.0.20220316"
  std::istringstream words(go.output);
  std::string name, version;
  words >> name >> version;
  return version.starts_with('v') ? version.substr(1) : version;
}

NetworkLink::NetworkLink(const LinkShaping& shaping, const NetworkLayout& layout) {
  std::string version;
  if (layout.vpn == NetworkLayout::Vpn::kWireguard) version = wireguard_version();
  if (geteuid() != 0) {
    throw NetworkSetupError(
        "--netns needs root (CAP_SYS_ADMIN and CAP_NET_ADMIN) to make network namespaces; run "
        "as root or leave out --netns");
  }
  remove_stale_namespaces();
  const std::string id = std::to_string(getpid());
  description_.runner_namespace = kPrefix + id + "-a";
  description_.remote_namespace = kPrefix + id + "-b";
  if (layout.topology == NetworkLayout::Topology::kRouted)
    description_.router_namespace = kPrefix + id + "-r";
  description_.mtu = kEthernetMtu;
  description_.layout = layout;
  description_.shaping = shaping;
  runner_device_ = "rp" + id + "a";
  remote_device_ = "rp" + id + "b";
  runner_traffic_device_ = runner_device_;
  if (!version.empty()) description_.tunnel = Tunnel{"wireguard-go", version, "", "", kEthernetMtu};
  try {
    make_path();
    if (description_.tunnel) make_tunnel();
  } catch (...) {
    remove();
    throw;
  }
}

// The namespaces, the veth pairs and routes between them, and the shaping on the hosts' ends.
void NetworkLink::make_path() {
  const std::string& a = description_.runner_namespace;
  const std::string& b = description_.remote_namespace;
  const std::string& r = description_.router_namespace;
  const std::string mtu = std::to_string(kEthernetMtu);
  for (const std::string& ns : {a, b, r}) {
    if (ns.empty()) continue;
    step({"ip", "netns", "add", ns});
    step({"ip", "-n", ns, "link", "set", "lo", "up"});
  }
  // {namespace, device, address/prefix}
  std::vector<std::tuple<std::string, std::string, std::string>> ends;
  if (r.empty()) {
    description_.runner_address = "10.200.0.1";
    description_.remote_address = "10.200.0.2";
    step({"ip", "link", "add", runner_device_, "mtu", mtu, "netns", a, "type", "veth", "peer",
          "name", remote_device_, "mtu", mtu, "netns", b});
    ends = {{a, runner_device_, "10.200.0.1/24"}, {b, remote_device_, "10.200.0.2/24"}};
  } else {
    description_.runner_address = "10.200.1.1";
    description_.remote_address = "10.200.2.2";
    const std::string router_a = runner_device_ + "r", router_b = remote_device_ + "r";
    step({"ip", "link", "add", runner_device_, "mtu", mtu, "netns", a, "type", "veth", "peer",
          "name", router_a, "mtu", mtu, "netns", r});
    step({"ip", "link", "add", remote_device_, "mtu", mtu, "netns", b, "type", "veth", "peer",
          "name", router_b, "mtu", mtu, "netns", r});
    ends = {{a, runner_device_, "10.200.1.1/24"},
            {b, remote_device_, "10.200.2.2/24"},
            {r, router_a, "10.200.1.254/24"},
            {r, router_b, "10.200.2.254/24"}};
    step({"ip", "netns", "exec", r, "sysctl", "-q", "-w", "net.ipv4.ip_forward=1"});
  }
  for (const auto& [ns, device, address] : ends) {
    step({"ip", "-n", ns, "addr", "add", address, "dev", device});
    step({"ip", "-n", ns, "link", "set", device, "up"});
  }
  if (r.empty()) {
    step({"ip", "-n", a, "route", "add", "default", "dev", runner_device_});
    step({"ip", "-n", b, "route", "add", "default", "dev", remote_device_});
  } else {
    // Each host reaches the other subnet through the router; multicast stays on its own.
    // The other subnet's own route outlasts a tunnel's taking the default one.
    step({"ip", "-n", a, "route", "add", "10.200.2.0/24", "via", "10.200.1.254"});
    step({"ip", "-n", b, "route", "add", "10.200.1.0/24", "via", "10.200.2.254"});
    step({"ip", "-n", a, "route", "add", "default", "via", "10.200.1.254"});
    step({"ip", "-n", b, "route", "add", "default", "via", "10.200.2.254"});
    description_.static_peers = {description_.runner_address, description_.remote_address};
  }
  shape(a, runner_device_, description_.shaping);
  shape(b, remote_device_, description_.shaping);
}

// A wireguard-go per host, with keys made for this run, peered over the path make_path made; the
// hosts' default routes go into the tunnel, so that all their traffic to each other crosses it.
void NetworkLink::make_tunnel() {
  Tunnel& tunnel = *description_.tunnel;
  tunnel.runner_endpoint = description_.runner_address;
  tunnel.remote_endpoint = description_.remote_address;
  const std::string id = std::to_string(getpid());
  std::string folder_template =
      (fs::temp_directory_path() / (kKeyFolderPrefix + id + "-XXXXXX")).string();
  if (mkdtemp(folder_template.data()) == nullptr)
    throw NetworkSetupError("--netns: cannot make a key folder in " +
                            fs::temp_directory_path().string() + ": " + std::strerror(errno));
  key_folder_ = folder_template;
  struct Host {
    std::string ns, device, endpoint, address, public_key;
  };
  std::array<Host, 2> hosts = {Host{description_.runner_namespace, "wg" + id + "a",
                                    tunnel.runner_endpoint, "10.201.0.1", ""},
                               Host{description_.remote_namespace, "wg" + id + "b",
                                    tunnel.remote_endpoint, "10.201.0.2", ""}};
  for (auto& host : hosts) {
    // wireguard-go makes the TUN device and its control socket before it goes to the background.
    step({"ip", "netns", "exec", host.ns, "wireguard-go", host.device});
    tunnel_devices_.emplace_back(host.ns, host.device);
    const fs::path key = write_private_key(key_folder_, host.device + ".key");
    step({"ip", "netns", "exec", host.ns, "wg", "set", host.device, "listen-port",
          std::to_string(kWireguardPort), "private-key", key.string()});
    const ToolRun shown =
        run_tool({"ip", "netns", "exec", host.ns, "wg", "show", host.device, "public-key"});
    const auto words = split_words(shown.output);
    if (shown.status != 0 || words.size() != 1)
      throw NetworkSetupError("--netns: wg show " + host.device +
                              " public-key failed: " + first_line(shown.output));
    host.public_key = words[0];
  }
  // The keys are in the daemons now.
  fs::remove_all(key_folder_);
  key_folder_.clear();
  for (std::size_t i = 0; i < hosts.size(); ++i) {
    const Host& self = hosts[i];
    const Host& peer = hosts[1 - i];
    step({"ip", "netns", "exec", self.ns, "wg", "set", self.device, "peer", peer.public_key,
          "allowed-ips", peer.address + "/32", "endpoint",
          peer.endpoint + ":" + std::to_string(kWireguardPort)});
    step({"ip", "-n", self.ns, "addr", "add", self.address + "/24", "dev", self.device});
    step({"ip", "-n", self.ns, "link", "set", self.device, "mtu", std::to_string(kWireguardMtu),
          "up"});
    step({"ip", "-n", self.ns, "route", "replace", "default", "dev", self.device});
  }
  description_.runner_address = hosts[0].address;
  description_.remote_address = hosts[1].address;
  description_.mtu = kWireguardMtu;
  description_.static_peers = {hosts[0].address, hosts[1].address};
  runner_traffic_device_ = hosts[0].device;
}

void NetworkLink::remove() {
  // Deleting its TUN device ends a wireguard-go; one still in a namespace would keep it alive.
  for (const auto& [ns, device] : tunnel_devices_)
    run_tool({"ip", "-n", ns, "link", "del", device});
  for (const std::string* ns : {&description_.remote_namespace, &description_.router_namespace,
                                &description_.runner_namespace}) {
    if (!ns->empty()) run_tool({"ip", "netns", "del", *ns});
  }
  std::error_code ec;
  if (!key_folder_.empty()) fs::remove_all(key_folder_, ec);
}

NetworkLink::~NetworkLink() {
  remove();
}

void NetworkLink::enter_runner_side() {
  const std::string path = std::string(kNetnsDir) + "/" + description_.runner_namespace;
  const int fd = open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0 || setns(fd, CLONE_NEWNET) != 0) {
    const std::string why = std::strerror(errno);
    if (fd >= 0) close(fd);
    throw NetworkSetupError("--netns: cannot enter " + path + ": " + why);
  }
  close(fd);
  if (!description_.static_peers.empty()) {
    std::string peers;
    for (const auto& p : description_.static_peers) peers += (peers.empty() ? "" : ";") + p;
    setenv("ROS_STATIC_PEERS", peers.c_str(), 1);
  }
}

std::vector<std::string> NetworkLink::launcher() const {
  return {"ip", "netns", "exec", description_.remote_namespace};
}

NetworkLink::Counters NetworkLink::counters() const {
  Counters c;
  const ToolRun run = run_tool({"ip", "-n", description_.runner_namespace, "-s", "-j", "link",
                                "show", "dev", runner_traffic_device_});
  const auto j = nlohmann::json::parse(run.output, nullptr, false);
  if (j.is_array() && !j.empty()) {
    c.bytes_out = json_u64(j[0], {"stats64", "tx", "bytes"});
    c.bytes_in = json_u64(j[0], {"stats64", "rx", "bytes"});
    c.packets_out = json_u64(j[0], {"stats64", "tx", "packets"});
    c.packets_in = json_u64(j[0], {"stats64", "rx", "packets"});
  }
  c.dropped = qdisc_drops(description_.runner_namespace, runner_device_) +
              qdisc_drops(description_.remote_namespace, remote_device_);
  return c;
}

}  // namespace robotperf::harness
