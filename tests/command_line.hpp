// Runs command lines for the end-to-end tests, as a user's shell would.
#pragma once

#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>
#include <thread>

namespace robotperf::test_support {

struct Outcome {
  int exit_code = -1;  // -1 when the command did not exit normally
  std::string out;     // stdout and stderr together
};

inline Outcome shell(const std::string& command) {
  Outcome o;
  FILE* p = popen((command + " 2>&1").c_str(), "r");
  if (p == nullptr) return o;
  std::array<char, 4096> buf;
  while (std::size_t n = fread(buf.data(), 1, buf.size(), p)) o.out.append(buf.data(), n);
  const int status = pclose(p);
  o.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return o;
}

#ifdef ROBOTPERF_EXECUTABLE
// The robotperf under test with `args`; `environment` (VAR=value ...) goes before it.
inline Outcome robotperf_cli(const std::string& args, const std::string& environment = "") {
  return shell(environment + " " + ROBOTPERF_EXECUTABLE + " " + args);
}
#endif

// A command line running in the background (through /bin/sh), its output going to `log`: for
// tests that signal a run while it goes on.
class Background {
 public:
  Background(const std::string& command, const std::filesystem::path& log) : log_(log) {
    const std::string line = "exec " + command + " >" + log.string() + " 2>&1";
    const char* argv[] = {"/bin/sh", "-c", line.c_str(), nullptr};
    if (posix_spawn(&pid_, "/bin/sh", nullptr, nullptr, const_cast<char* const*>(argv), environ) !=
        0)
      pid_ = -1;
  }
  ~Background() {
    if (pid_ > 0 && !exited_) {
      kill(pid_, SIGKILL);
      waitpid(pid_, nullptr, 0);
    }
  }
  Background(const Background&) = delete;
  Background& operator=(const Background&) = delete;

  pid_t pid() const { return pid_; }
  void signal(int signal_number) const { kill(pid_, signal_number); }
  // The exit status, or -1 when it did not exit within `timeout` (it is then killed) or was
  // killed by a signal.
  int wait(std::chrono::seconds timeout) {
    const auto end = std::chrono::steady_clock::now() + timeout;
    int status = 0;
    while (waitpid(pid_, &status, WNOHANG) == 0) {
      if (std::chrono::steady_clock::now() > end) return -1;
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    exited_ = true;
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  }
  std::string output() const {
    std::ifstream in(log_);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
  }

 private:
  std::filesystem::path log_;
  pid_t pid_ = -1;
  bool exited_ = false;
};

// Polls `condition` until it holds or `timeout` passes: for events another process signals only
// through the file system.
inline bool eventually(const std::function<bool()>& condition, std::chrono::seconds timeout) {
  const auto end = std::chrono::steady_clock::now() + timeout;
  while (!condition()) {
    if (std::chrono::steady_clock::now() > end) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return true;
}

}  // namespace robotperf::test_support
