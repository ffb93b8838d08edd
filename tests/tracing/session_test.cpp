// A recording session against fake lttng and lttng-sessiond programs: what becomes of a session
// daemon that robotperf started once its session ends, whatever lttng-tools version says so.
#include "robotperf/tracing/session.hpp"

#include <grp.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <string>
#include <vector>

#include "../test_file_name.hpp"
#include "lttng_command.hpp"
#include "ownership.hpp"
#include "robotperf/tracing/leftovers.hpp"

namespace robotperf::tracing {
namespace {

namespace fs = std::filesystem;

// How the fake lttng behaves: the wording of `lttng list` without sessions ("tracing" before
// lttng-tools 2.13, "recording" since), and whether its first `lttng destroy` fails.
struct FakeTools {
  std::string session_noun;
  bool first_destroy_fails = false;
};

// What a child process that made a session and stopped it left behind.
struct Outcome {
  bool stop_threw = false;
  bool daemon_exited = false;  // the daemon started for the session, awaited
  bool sessions_left = false;
};

class SessionWithFakeLttng : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("robotperf-session-" + std::to_string(getpid()) + "-" +
                                        robotperf::testing::current_test_file_name());
    fs::remove_all(dir_);
    for (const char* d : {"bin", "home", "state"}) fs::create_directories(dir_ / d);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // Writes the fakes: sessions are files in state/, the daemon is a `sleep` whose pid is where
  // session.cpp looks for the daemon's (under $LTTNG_HOME).
  void write_fakes(const FakeTools& tools) {
    const std::string state = (dir_ / "state").string();
    if (tools.first_destroy_fails) std::ofstream(dir_ / "state" / "fail-destroy");
    std::ofstream(dir_ / "bin" / "lttng")
        << "#!/bin/sh\n"
           "S='"
        << state
        << "'\n"
           "pid=$(cat \"$LTTNG_HOME/.lttng/lttng-sessiond.pid\" 2>/dev/null)\n"
           "case \"$1\" in\n"
           "  list)\n"
           "    if [ -z \"$pid\" ] || ! kill -0 \"$pid\" 2>/dev/null; then\n"
           "      echo 'Error: No session daemon is available'; exit 1\n"
           "    fi\n"
           "    if [ \"$2\" = --userspace ]; then echo \"PID: $PPID - Name: test\"; exit 0; fi\n"
           "    if ls \"$S\"/session-* >/dev/null 2>&1; then echo 'Available "
        << tools.session_noun
        << " sessions:'\n"
           "    else echo 'Currently no available "
        << tools.session_noun
        << " session'; fi ;;\n"
           "  create) touch \"$S/session-$2\" ;;\n"
           "  destroy)\n"
           "    if [ -f \"$S/fail-destroy\" ]; then\n"
           "      rm \"$S/fail-destroy\"; echo 'Error: Session destruction failed'; exit 1\n"
           "    fi\n"
           "    rm -f \"$S/session-$2\" ;;\n"
           "esac\n"
           "exit 0\n";
    std::ofstream(dir_ / "bin" / "lttng-sessiond")
        << "#!/bin/sh\n"
           "mkdir -p \"$LTTNG_HOME/.lttng\"\n"
           "sleep 3600 </dev/null >/dev/null 2>&1 &\n"
           "echo $! > \"$LTTNG_HOME/.lttng/lttng-sessiond.pid\"\n";
    for (const char* f : {"lttng", "lttng-sessiond"}) {
      fs::permissions(dir_ / "bin" / f, fs::perms::owner_all | fs::perms::group_read |
                                            fs::perms::group_exec | fs::perms::others_read |
                                            fs::perms::others_exec);
    }
    // Written by the child, who is nobody when the test runs as root.
    for (const char* d : {"home", "state"}) fs::permissions(dir_ / d, fs::perms::all);
  }

  // Runs `body` in a child process with the fakes first on PATH; its exit status, -1 when it did
  // not exit. Run as root, the child is nobody: root's daemon writes its pid in /var/run/lttng,
  // where a real daemon's may be.
  int in_child(const std::function<int()>& body) {
    const pid_t child = fork();
    if (child == 0) {
      if (getuid() == 0 && (setgroups(0, nullptr) != 0 || setgid(65534) != 0 || setuid(65534) != 0))
        _exit(3);
      setenv("PATH", ((dir_ / "bin").string() + ":/usr/bin:/bin").c_str(), 1);
      setenv("LTTNG_HOME", (dir_ / "home").c_str(), 1);
      int code = 1;
      try {
        code = body();
      } catch (const std::exception& e) {
        std::cerr << e.what() << "\n";
      }
      _exit(code);
    }
    int status = 0;
    waitpid(child, &status, 0);
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  }

  // Makes a session in a child process and stops it. The daemon inherits the write end of a
  // pipe, whose end says it exited.
  Outcome make_and_stop_session() {
    int fds[2];
    if (pipe(fds) != 0) throw std::runtime_error("pipe");
    const int code = in_child([&] {
      close(fds[0]);
      SessionOptions options;
      options.output_dir = dir_ / "trace";
      RecordingSession session(options);
      if (!session.started_daemon()) return 4;
      try {
        session.stop();
      } catch (const TracingError& e) {
        std::cerr << e.what() << "\n";
        return 10;
      }
      return 0;
    });
    close(fds[1]);
    Outcome out;
    EXPECT_TRUE(code == 0 || code == 10) << "the child failed with status " << code;
    out.stop_threw = code == 10;
    // End of file once every holder of the write end is gone: the daemon last.
    pollfd p{fds[0], POLLIN, 0};
    char byte;
    out.daemon_exited = poll(&p, 1, 30'000) == 1 && read(fds[0], &byte, 1) == 0;
    close(fds[0]);
    if (!out.daemon_exited) {
      std::ifstream in(dir_ / "home" / ".lttng" / "lttng-sessiond.pid");
      if (pid_t pid = 0; in >> pid && pid > 0) kill(pid, SIGKILL);
    }
    for (const auto& f : fs::directory_iterator(dir_ / "state"))
      out.sessions_left |= f.path().filename().string().starts_with("session-");
    return out;
  }

  fs::path dir_;
};

// lttng-tools before 2.13 (Debian bullseye's 2.12, Ubuntu 20.04's 2.11) says "tracing session".
TEST_F(SessionWithFakeLttng, ADaemonStartedForASessionEndsWithItBeforeLttng213) {
  write_fakes({.session_noun = "tracing"});
  const Outcome out = make_and_stop_session();
  EXPECT_FALSE(out.stop_threw);
  EXPECT_FALSE(out.sessions_left);
  EXPECT_TRUE(out.daemon_exited);
}

TEST_F(SessionWithFakeLttng, ADaemonStartedForASessionEndsWithItOnLttng213) {
  write_fakes({.session_noun = "recording"});
  const Outcome out = make_and_stop_session();
  EXPECT_FALSE(out.stop_threw);
  EXPECT_FALSE(out.sessions_left);
  EXPECT_TRUE(out.daemon_exited);
}

// stop() says that destroying the session failed, and the destructor destroys it: no session
// is left, and so the daemon started for it ends.
TEST_F(SessionWithFakeLttng, ASessionThatFailedToBeDestroyedIsDestroyedByTheDestructor) {
  write_fakes({.session_noun = "recording", .first_destroy_fails = true});
  const Outcome out = make_and_stop_session();
  EXPECT_TRUE(out.stop_threw);
  EXPECT_FALSE(out.sessions_left);
  EXPECT_TRUE(out.daemon_exited);
}

// A run killed before it could stop the daemon it started leaves it to the next run's clean-up,
// which must not stop it while another run holds it (found it answering and is about to make its
// session there): only once no run holds it.
TEST_F(SessionWithFakeLttng, LeftoversNeverStopADaemonARunIsAboutToUse) {
  write_fakes({.session_noun = "recording"});
  fs::create_directories(dir_ / "results");
  const int code = in_child([&] {
    if (!ensure_session_daemon()) return 4;
    const pid_t daemon = detail::daemon_pid();
    // Its starter: a process that no longer runs (no process started at tick 1 of this boot).
    detail::ProcessIdentity starter = detail::this_process();
    starter.start_ticks = 1;
    detail::write_daemon_ownership({detail::process_identity(daemon), starter});
    {
      const detail::DaemonUseLock about_to_use = detail::DaemonUseLock::shared();
      remove_leftovers(dir_ / "results");
      if (kill(daemon, 0) != 0) return 5;
    }
    const std::vector<std::string> removed = remove_leftovers(dir_ / "results");
    if (removed.size() != 1 || removed[0].find("session daemon") == std::string::npos) return 6;
    return kill(daemon, 0) == 0 ? 7 : 0;
  });
  EXPECT_NE(code, 5) << "the clean-up stopped a daemon a run held";
  EXPECT_NE(code, 6) << "the clean-up did not stop the daemon once no run held it";
  EXPECT_EQ(code, 0);
}

// A session holds the daemon from before it looks for one until it is destroyed.
TEST_F(SessionWithFakeLttng, ASessionHoldsTheDaemonForItsWholeLife) {
  write_fakes({.session_noun = "recording"});
  const int code = in_child([&] {
    {
      SessionOptions options;
      options.output_dir = dir_ / "trace";
      RecordingSession session(options);
      if (detail::DaemonUseLock::alone_if_unused()) return 5;
      session.stop();
      if (detail::DaemonUseLock::alone_if_unused()) return 6;
    }
    return detail::DaemonUseLock::alone_if_unused() ? 0 : 7;
  });
  EXPECT_EQ(code, 0) << "5, 6: the lock was free while the session lived; 7: it stayed held";
}

}  // namespace
}  // namespace robotperf::tracing
