#include "ownership.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <atomic>
#include <cctype>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "lttng_command.hpp"

namespace robotperf::tracing::detail {
namespace {

namespace fs = std::filesystem;

constexpr const char* kSessionPrefix = "robotperf-";
constexpr uint64_t kMaxPid = 4194304;  // the kernel's PID_MAX_LIMIT

std::string current_boot_id() {
  std::string id;
  std::ifstream("/proc/sys/kernel/random/boot_id") >> id;
  return id;
}

// Field 22 of /proc/<pid>/stat, counted after the command name (which may hold spaces and
// parentheses, so from its last ')').
uint64_t start_ticks_of(pid_t pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/stat");
  std::string stat((std::istreambuf_iterator<char>(in)), {});
  const auto name_end = stat.rfind(')');
  if (name_end == std::string::npos) return 0;
  std::istringstream fields(stat.substr(name_end + 1));
  std::string field;
  for (int i = 3; i <= 22 && fields >> field; ++i) {
    if (i == 22) return std::strtoull(field.c_str(), nullptr, 10);
  }
  return 0;
}

std::optional<uint64_t> number(const std::string& text) {
  if (text.empty() || text.size() > 19) return std::nullopt;
  for (char c : text) {
    if (!std::isdigit(static_cast<unsigned char>(c))) return std::nullopt;
  }
  return std::strtoull(text.c_str(), nullptr, 10);
}

}  // namespace

ProcessIdentity process_identity(pid_t pid) {
  return {pid, start_ticks_of(pid), current_boot_id()};
}

ProcessIdentity this_process() {
  return process_identity(getpid());
}

bool still_runs(const ProcessIdentity& process) {
  if (process.pid <= 0 || process.boot_id != current_boot_id()) return false;
  const uint64_t start = start_ticks_of(process.pid);
  return start != 0 && start == process.start_ticks;
}

std::string text_of(const ProcessIdentity& process) {
  return std::to_string(process.pid) + " " + std::to_string(process.start_ticks) + " " +
         process.boot_id;
}

std::optional<ProcessIdentity> parse_identity(const std::string& text) {
  std::istringstream in(text);
  std::string pid, start, boot;
  if (!(in >> pid >> start >> boot)) return std::nullopt;
  const auto p = number(pid);
  const auto s = number(start);
  if (!p || !s || *p == 0 || *p > kMaxPid) return std::nullopt;
  return ProcessIdentity{static_cast<pid_t>(*p), *s, boot};
}

std::string new_session_name(const std::string& hint) {
  static std::atomic<unsigned> counter{0};
  static const ProcessIdentity self = this_process();
  std::string clean;
  for (char c : hint) clean += (std::isalnum(static_cast<unsigned char>(c)) || c == '_') ? c : '_';
  return kSessionPrefix + clean + "-" + std::to_string(self.pid) + "-s" +
         std::to_string(self.start_ticks) + "-" + std::to_string(counter++);
}

std::optional<ProcessIdentity> session_maker(const std::string& name) {
  if (!name.starts_with(kSessionPrefix)) return std::nullopt;
  // From the end: the counter, the start ticks, the pid (the hint has no '-').
  const auto counter_dash = name.rfind('-');
  if (counter_dash == std::string::npos || counter_dash == 0) return std::nullopt;
  const auto start_dash = name.rfind('-', counter_dash - 1);
  if (start_dash == std::string::npos || start_dash == 0) return std::nullopt;
  const auto pid_dash = name.rfind('-', start_dash - 1);
  if (pid_dash == std::string::npos || pid_dash < std::string_view(kSessionPrefix).size() - 1)
    return std::nullopt;
  const std::string start = name.substr(start_dash + 1, counter_dash - start_dash - 1);
  const auto pid = number(name.substr(pid_dash + 1, start_dash - pid_dash - 1));
  if (!number(name.substr(counter_dash + 1)) || !start.starts_with('s')) return std::nullopt;
  const auto ticks = number(start.substr(1));
  if (!pid || !ticks || *pid == 0 || *pid > kMaxPid) return std::nullopt;
  return ProcessIdentity{static_cast<pid_t>(*pid), *ticks, current_boot_id()};
}

fs::path daemon_owner_file() {
  return daemon_pid_file().parent_path() / "robotperf-started-sessiond";
}

void write_daemon_ownership(const DaemonOwnership& ownership) {
  std::ofstream(daemon_owner_file()) << text_of(ownership.daemon) << "\n"
                                     << text_of(ownership.starter) << "\n";
}

std::optional<DaemonOwnership> read_daemon_ownership() {
  std::ifstream in(daemon_owner_file());
  std::string daemon, starter;
  if (!std::getline(in, daemon) || !std::getline(in, starter)) return std::nullopt;
  auto d = parse_identity(daemon);
  auto s = parse_identity(starter);
  if (!d || !s) return std::nullopt;
  return DaemonOwnership{*d, *s};
}

fs::path daemon_use_lock_file() {
  return daemon_pid_file().parent_path() / "robotperf-sessiond-users.lock";
}

namespace {

// The lock file opened (made when missing, never through a symlink), or -1 with `why`.
int open_daemon_use_lock(std::string& why) {
  const fs::path file = daemon_use_lock_file();
  std::error_code ec;
  fs::create_directories(file.parent_path(), ec);
  const int fd = ::open(file.c_str(), O_RDWR | O_CREAT | O_NOFOLLOW | O_CLOEXEC, 0600);
  if (fd < 0) why = "cannot open " + file.string() + ": " + std::strerror(errno);
  return fd;
}

}  // namespace

DaemonUseLock DaemonUseLock::shared() {
  std::string why;
  const int fd = open_daemon_use_lock(why);
  if (fd < 0) throw std::runtime_error(why);
  while (::flock(fd, LOCK_SH) != 0) {
    if (errno != EINTR) {
      why = std::strerror(errno);
      ::close(fd);
      throw std::runtime_error("cannot lock " + daemon_use_lock_file().string() + ": " + why);
    }
  }
  return DaemonUseLock(fd);
}

std::optional<DaemonUseLock> DaemonUseLock::alone_if_unused() {
  std::string why;
  const int fd = open_daemon_use_lock(why);
  if (fd < 0) return std::nullopt;
  if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
    ::close(fd);
    return std::nullopt;
  }
  return DaemonUseLock(fd);
}

DaemonUseLock::DaemonUseLock(DaemonUseLock&& other) noexcept : fd_(std::exchange(other.fd_, -1)) {}

DaemonUseLock& DaemonUseLock::operator=(DaemonUseLock&& other) noexcept {
  if (this != &other) {
    if (fd_ >= 0) ::close(fd_);
    fd_ = std::exchange(other.fd_, -1);
  }
  return *this;
}

DaemonUseLock::~DaemonUseLock() {
  if (fd_ >= 0) ::close(fd_);
}

}  // namespace robotperf::tracing::detail
