// The processes a run starts besides its own: an external graph's launched commands and the
// children of a per-node run, with what those start in turn.
#include <gtest/gtest.h>
#include <linux/filter.h>
#include <linux/seccomp.h>
#include <poll.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstddef>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <future>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "../fixture_root.hpp"
#include "launched_processes.hpp"
#include "measurement.hpp"
#include "node_processes.hpp"
#include "process_table.hpp"
#include "robotperf/harness/run.hpp"
#include "test_package.hpp"

namespace robotperf::harness {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

using robotperf::testing::FixtureRoot;

BenchmarkSpec launching(const fs::path& dir, const std::vector<std::string>& command) {
  BenchmarkSpec spec;
  spec.dir = dir;
  spec.launch.push_back({"graph", command, ".", {}});
  return spec;
}

// The members of process group `group` that still run (not zombies).
std::vector<pid_t> running_members(pid_t group) {
  std::vector<pid_t> out;
  for (const auto& p : list_processes()) {
    if (p.pgrp == group && p.state != 'Z') out.push_back(p.pid);
  }
  return out;
}

// The running processes whose command line holds `marker`.
std::vector<pid_t> processes_running(const std::string& marker) {
  std::vector<pid_t> out;
  for (const auto& p : list_processes()) {
    std::ifstream in("/proc/" + std::to_string(p.pid) + "/cmdline");
    const std::string cmdline(std::istreambuf_iterator<char>(in), {});
    if (p.state != 'Z' && cmdline.find(marker) != std::string::npos) out.push_back(p.pid);
  }
  return out;
}

// The processes of `pids` that have not ended within `limit`. kill() returns before the signal
// is delivered, so a process killed a moment ago can still be listed as running; its pidfd
// becomes readable when it ends, which is the event to await.
std::vector<pid_t> outliving(const std::vector<pid_t>& pids, std::chrono::milliseconds limit) {
  std::vector<pid_t> out;
  const auto deadline = std::chrono::steady_clock::now() + limit;
  for (const pid_t pid : pids) {
    const int fd = static_cast<int>(syscall(SYS_pidfd_open, pid, 0));
    if (fd < 0) continue;  // already gone
    pollfd ended{fd, POLLIN, 0};
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        deadline - std::chrono::steady_clock::now());
    if (poll(&ended, 1, static_cast<int>(std::max<long long>(left.count(), 0))) != 1)
      out.push_back(pid);
    close(fd);
  }
  return out;
}

// `ros2 run`, `ros2 launch` and wrapper scripts run the node as their child: its CPU is the
// launched process's, not another process's.
TEST(LaunchedProcesses, TheCpuOfALaunchedCommandsChildrenIsItsOwn) {
  FixtureRoot scratch;
  // `; true` keeps the shell waiting for the busy child instead of becoming it.
  LaunchedProcesses launched(launching(scratch.path(), {"sh", "-c", "yes > /dev/null; true"}),
                             "fastdds", 0, scratch.path(), "cpu.");
  const auto [pid, name] = launched.processes().at(0);
  // The window opens once the busy child runs: on a loaded machine the shell may take a while to
  // start it, and a window before that measures nothing of it.
  const auto deadline = std::chrono::steady_clock::now() + 10s;
  while (running_members(pid).size() < 2 && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(5ms);
  ASSERT_GE(running_members(pid).size(), 2u) << "the shell never started its child";
  RunOptions options;
  WindowMeasurement measurement(options, {{pid, name}}, {pid});
  measurement.begin();
  // The window: the busy child runs in it.
  std::this_thread::sleep_for(500ms);
  RunResult r;
  measurement.end(r);
  launched.stop(0.2);
  ASSERT_TRUE(r.resources.measured);
  ASSERT_EQ(r.resources.processes.size(), 1u);
  const metrics::ProcessUsage& usage = r.resources.processes[0];
  ASSERT_TRUE(usage.measured) << usage.error;
  // The shell itself only waits: all of this is its child's (a tick is 10 ms).
  EXPECT_GT(usage.cpu_user_s + usage.cpu_system_s, 0.02);
  EXPECT_GT(usage.cpu_percent, 4.0);
}

// A member of the group that ignores SIGINT and SIGTERM (here a background job of the launched
// shell) outlives the processes robotperf started; it must still get SIGKILL.
TEST(LaunchedProcesses, StoppingKillsTheWholeGroupEvenAfterTheLaunchedProcessEnded) {
  FixtureRoot scratch;
  LaunchedProcesses launched(
      launching(scratch.path(),
                {"sh", "-c", "(trap '' INT TERM; exec sleep 299) & exec sleep 300"}),
      "fastdds", 0, scratch.path(), "stop.");
  const pid_t group = launched.processes().at(0).first;
  // The background job is up once it is in the group beside the shell.
  const auto deadline = std::chrono::steady_clock::now() + 10s;
  while (running_members(group).size() < 2 && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(10ms);
  ASSERT_EQ(running_members(group).size(), 2u);
  EXPECT_EQ(launched.stop(0.2).size(), 1u);
  EXPECT_EQ(outliving(running_members(group), 10s), std::vector<pid_t>{})
      << "a member of the group still runs";
  kill(-group, SIGKILL);
}

// Makes pidfd_open fail in the calling thread (and the threads it starts) as on a kernel before
// 5.3; false where seccomp filters cannot be installed.
bool refuse_pidfd_open() {
  sock_filter filter[] = {
      BPF_STMT(BPF_LD | BPF_W | BPF_ABS, offsetof(seccomp_data, nr)),
      BPF_JUMP(BPF_JMP | BPF_JEQ | BPF_K, SYS_pidfd_open, 0, 1),
      BPF_STMT(BPF_RET | BPF_K, SECCOMP_RET_ERRNO | ENOSYS),
      BPF_STMT(BPF_RET | BPF_K, SECCOMP_RET_ALLOW),
  };
  sock_fprog program{static_cast<unsigned short>(std::size(filter)), filter};
  return prctl(PR_SET_NO_NEW_PRIVS, 1, 0, 0, 0) == 0 &&
         syscall(SYS_seccomp, SECCOMP_SET_MODE_FILTER, 0, &program) == 0;
}

// Without a pidfd (an older kernel, or no descriptor left) a launched process is still watched:
// its end during the run is a failure with how it ended.
TEST(LaunchedProcesses, AProcessWithoutAPidfdIsStillSupervised) {
  FixtureRoot scratch;
  std::unique_ptr<LaunchedProcesses> launched;
  bool refused = false;
  // In a thread of its own: the filter stays with the thread, not the rest of the tests.
  std::thread([&] {
    refused = refuse_pidfd_open();
    if (refused) {
      launched = std::make_unique<LaunchedProcesses>(
          launching(scratch.path(), {"sh", "-c", "sleep 0.5; exit 3"}), "fastdds", 0,
          scratch.path(), "nopidfd.");
    }
  }).join();
  if (!refused) GTEST_SKIP() << "seccomp filters are not available here";
  const auto deadline = std::chrono::steady_clock::now() + 20s;
  while (launched->failure().empty() && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(20ms);
  const std::string failure = launched->failure();
  EXPECT_NE(failure.find("ended during the run (exited with status 3)"), std::string::npos)
      << failure;
  launched->stop(0.2);
}

BenchmarkSpec with_nodes(const fs::path& dir, const std::vector<std::string>& hosts) {
  BenchmarkSpec spec;
  spec.dir = dir;
  for (std::size_t i = 0; i < hosts.size(); ++i) {
    NodeSpec node;
    node.name = "n" + std::to_string(i);
    node.kernel = "util/relay";
    node.host = hosts[i];
    spec.nodes.push_back(node);
  }
  return spec;
}

// A child that does not stop is killed with what it started: a process of its own holding the
// child's stdout open must not keep the runner waiting for its end.
TEST(NodeProcesses, ShutdownEndsAChildWhoseOwnChildHoldsItsOutputOpen) {
  FixtureRoot scratch;
  auto children = std::make_shared<NodeProcesses>(
      with_nodes(scratch.path(), {""}),
      std::vector<std::string>{"sh", "-c", "sleep 1000 & while :; do sleep 1; done"}, "fastdds", 0);
  const pid_t group = children->processes().at(0).first;
  auto reports = std::async(std::launch::async, [children] { return children->shutdown(0.5); });
  const bool ended = reports.wait_for(20s) == std::future_status::ready;
  // Either way, nothing is left behind (and a hung shutdown can end).
  kill(-group, SIGKILL);
  ASSERT_TRUE(ended) << "shutdown did not return";
  const std::vector<NodeReport> nodes = reports.get();
  ASSERT_EQ(nodes.size(), 1u);
  EXPECT_EQ(nodes[0].exit_status, "did not stop within 0.5 s after the run: killed");
}

// A node whose process cannot start takes the ones started before it down with it.
TEST(NodeProcesses, AChildThatCannotStartTakesTheOthersWithIt) {
  FixtureRoot scratch;
  const std::string marker = "robotperf-test-" + std::to_string(getpid()) + "-start";
  EXPECT_THROW(NodeProcesses(with_nodes(scratch.path(), {"", "nowhere"}),
                             {"sh", "-c", "sleep 1000; true # " + marker}, "fastdds", 0, {},
                             {{"nowhere", {"/nonexistent/robotperf-test-launcher"}}}),
               std::runtime_error);
  const std::vector<pid_t> left = outliving(processes_running(marker), 10s);
  EXPECT_TRUE(left.empty()) << "the first node's process still runs";
  for (const pid_t pid : left) kill(pid, SIGKILL);
}

// A node process waits for its peers as long as the runner does: when the runner gives up (its
// --connect-timeout), it closes the child's stdin, and the child ends then.
TEST(NodeProcessDeathTest, AChildThatNeverConnectsEndsWhenTheRunnerGivesUp) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  testing::TestPackage p("never_connects", testing::relay_graph(""));
  const BenchmarkSpec spec = load_benchmark(p.dir());
  EXPECT_EXIT(
      {
        // The runner has already given up: stdin is at its end from the start.
        int to_child[2];
        if (pipe(to_child) != 0 || dup2(to_child[0], STDIN_FILENO) < 0) std::_Exit(2);
        close(to_child[0]);
        close(to_child[1]);
        // Its lines to the runner are not this test's.
        if (!std::freopen("/dev/null", "w", stdout)) std::_Exit(2);
        const auto start = std::chrono::steady_clock::now();
        // On intra, the relay's input has no publisher: it never connects.
        run_node_process(spec, "relay", "intra", 0);
        std::_Exit(std::chrono::steady_clock::now() - start < 20s ? 0 : 1);
      },
      ::testing::ExitedWithCode(0), "");
}

}  // namespace
}  // namespace robotperf::harness
