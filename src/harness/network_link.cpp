#include "robotperf/harness/network_link.hpp"

#include <fcntl.h>
#include <sched.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <sstream>

#include "node_processes.hpp"

extern char** environ;

namespace robotperf::harness {
namespace {

namespace fs = std::filesystem;

constexpr const char* kPrefix = "robotperf-";
constexpr const char* kNetnsDir = "/run/netns";

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

// The namespaces robotperf made for processes that have ended (a run killed before it could
// remove them).
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
    if (kill(static_cast<pid_t>(pid), 0) != 0 && errno == ESRCH)
      run_tool({"ip", "netns", "del", name});
  }
}

std::vector<std::string> split_words(const std::string& text) {
  std::istringstream in(text);
  std::vector<std::string> out;
  for (std::string w; in >> w;) out.push_back(w);
  return out;
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
  const std::vector<std::string> tbf = {
      "tbf", "rate", shaping.rate, "burst", burst_for(shaping.rate), "limit", "32mb"};
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
      args.insert(args.end(), tbf.begin(), tbf.end());
      step(args);
    }
  } else if (!shaping.rate.empty()) {
    std::vector<std::string> args = tc;
    args.push_back("root");
    args.insert(args.end(), tbf.begin(), tbf.end());
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

}  // namespace

NetworkLink::NetworkLink(const LinkShaping& shaping) {
  if (geteuid() != 0) {
    throw NetworkSetupError(
        "--netns needs root (CAP_SYS_ADMIN and CAP_NET_ADMIN) to make network namespaces; run "
        "as root or leave out --netns");
  }
  remove_stale_namespaces();
  const std::string id = std::to_string(getpid());
  description_.runner_namespace = kPrefix + id + "-a";
  description_.remote_namespace = kPrefix + id + "-b";
  description_.runner_address = "10.200.0.1";
  description_.remote_address = "10.200.0.2";
  description_.mtu = 1500;  // Ethernet's, as between two robot computers
  description_.shaping = shaping;
  runner_device_ = "rp" + id + "a";
  remote_device_ = "rp" + id + "b";
  const std::string& a = description_.runner_namespace;
  const std::string& b = description_.remote_namespace;
  step({"ip", "netns", "add", a});
  try {
    step({"ip", "netns", "add", b});
    step({"ip", "link", "add", runner_device_, "mtu", "1500", "netns", a, "type", "veth", "peer",
          "name", remote_device_, "mtu", "1500", "netns", b});
    for (const auto& [ns, device, address] :
         {std::tuple{a, runner_device_, description_.runner_address},
          std::tuple{b, remote_device_, description_.remote_address}}) {
      step({"ip", "-n", ns, "link", "set", "lo", "up"});
      step({"ip", "-n", ns, "addr", "add", address + "/24", "dev", device});
      step({"ip", "-n", ns, "link", "set", device, "up"});
      step({"ip", "-n", ns, "route", "add", "default", "dev", device});
      shape(ns, device, shaping);
    }
  } catch (...) {
    run_tool({"ip", "netns", "del", b});
    run_tool({"ip", "netns", "del", a});
    throw;
  }
}

NetworkLink::~NetworkLink() {
  run_tool({"ip", "netns", "del", description_.remote_namespace});
  run_tool({"ip", "netns", "del", description_.runner_namespace});
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
}

std::vector<std::string> NetworkLink::launcher() const {
  return {"ip", "netns", "exec", description_.remote_namespace};
}

NetworkLink::Counters NetworkLink::counters() const {
  Counters c;
  const ToolRun run = run_tool({"ip", "-n", description_.runner_namespace, "-s", "-j", "link",
                                "show", "dev", runner_device_});
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
