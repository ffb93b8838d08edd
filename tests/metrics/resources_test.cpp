// Resource usage of processes and the machine over a window: fixture /proc trees with known
// counters, and this process burning CPU.
#include "robotperf/metrics/resources.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>

namespace robotperf::metrics {
namespace {

namespace fs = std::filesystem;

constexpr int64_t kSecond = 1'000'000'000;

class FixtureProc {
 public:
  FixtureProc() {
    const auto* test = ::testing::UnitTest::GetInstance()->current_test_info();
    root_ = fs::temp_directory_path() /
            ("robotperf_resources_" + std::string(test->name()) + "_" + std::to_string(::getpid()));
    fs::remove_all(root_);
  }
  ~FixtureProc() { fs::remove_all(root_); }
  const fs::path& path() const { return root_; }
  void write(const std::string& relative, const std::string& content) const {
    const fs::path file = root_ / relative;
    fs::create_directories(file.parent_path());
    std::ofstream(file, std::ios::binary) << content;
  }
  // A process whose command name holds a space and a parenthesis, with two threads.
  void process(int pid, uint64_t minflt, uint64_t majflt, uint64_t utime, uint64_t stime,
               uint64_t hwm_kb, uint64_t vol0, uint64_t invol0, uint64_t vol1, uint64_t invol1) {
    const std::string p = std::to_string(pid);
    write(p + "/stat", p + " (robot perf) node) S 1 1 1 0 -1 4194560 " + std::to_string(minflt) +
                           " 0 " + std::to_string(majflt) + " 0 " + std::to_string(utime) + " " +
                           std::to_string(stime) + " 0 0 20 0 3 0 100 1000000 200\n");
    write(p + "/status", "Name:\trobot perf\nVmHWM:\t  " + std::to_string(hwm_kb) +
                             " kB\nVmRSS:\t 1000 kB\nvoluntary_ctxt_switches:\t1\n"
                             "nonvoluntary_ctxt_switches:\t1\n");
    write(p + "/task/" + p + "/status", "voluntary_ctxt_switches:\t" + std::to_string(vol0) +
                                            "\nnonvoluntary_ctxt_switches:\t" +
                                            std::to_string(invol0) + "\n");
    write(p + "/task/" + std::to_string(pid + 1) + "/status",
          "voluntary_ctxt_switches:\t" + std::to_string(vol1) + "\nnonvoluntary_ctxt_switches:\t" +
              std::to_string(invol1) + "\n");
  }
  // Two CPUs; `busy0` and `busy1` ticks of user time, `idle0`/`idle1` of idle time.
  void stat(uint64_t busy0, uint64_t idle0, uint64_t busy1, uint64_t idle1) {
    auto line = [](const std::string& name, uint64_t busy, uint64_t idle) {
      return name + " " + std::to_string(busy) + " 0 0 " + std::to_string(idle) + " 0 0 0 0 0 0\n";
    };
    write("stat", line("cpu ", busy0 + busy1, idle0 + idle1) + line("cpu0", busy0, idle0) +
                      line("cpu1", busy1, idle1) + "intr 12345\nctxt 999\n");
  }

 private:
  fs::path root_;
};

TEST(ResourceMonitor, FixtureCountersGiveExactUsage) {
  const double hz = static_cast<double>(::sysconf(_SC_CLK_TCK));
  FixtureProc proc;
  proc.process(4242, 100, 2, 1000, 500, 20'000, 10, 1, 5, 0);
  proc.stat(10'000, 50'000, 20'000, 40'000);
  ResourceMonitor monitor(proc.path(), {{4242, "rectify"}, {999, "gone"}});
  monitor.begin(0);
  // Over 2 s: the process used 1.5 s user + 0.5 s system; CPU 0 was busy 75 %, CPU 1 25 %.
  const auto ticks = [hz](double s) { return static_cast<uint64_t>(s * hz); };
  proc.process(4242, 160, 3, 1000 + ticks(1.5), 500 + ticks(0.5), 30'000, 30, 4, 6, 2);
  proc.stat(10'000 + ticks(1.5), 50'000 + ticks(0.5), 20'000 + ticks(0.5), 40'000 + ticks(1.5));
  monitor.end(2 * kSecond);

  const ResourceUsage u = monitor.usage();
  ASSERT_TRUE(u.measured);
  EXPECT_DOUBLE_EQ(u.window_s, 2.0);
  ASSERT_EQ(u.processes.size(), 2u);
  const auto& p = u.processes[0];
  ASSERT_TRUE(p.measured) << p.error;
  EXPECT_EQ(p.label, "rectify");
  EXPECT_NEAR(p.cpu_user_s, 1.5, 1e-9);
  EXPECT_NEAR(p.cpu_system_s, 0.5, 1e-9);
  EXPECT_NEAR(p.cpu_percent, 100.0, 1e-9);
  EXPECT_EQ(p.peak_rss_bytes, 30'000u * 1024);
  EXPECT_EQ(p.voluntary_switches, 21u);  // (30 + 6) - (10 + 5), over both threads
  EXPECT_EQ(p.involuntary_switches, 5u);
  EXPECT_EQ(p.minor_faults, 60u);
  EXPECT_EQ(p.major_faults, 1u);
  EXPECT_FALSE(u.processes[1].measured);
  EXPECT_NE(u.processes[1].error.find("999"), std::string::npos);

  ASSERT_EQ(u.per_cpu_busy_percent.size(), 2u);
  EXPECT_NEAR(u.per_cpu_busy_percent[0], 75.0, 1e-9);
  EXPECT_NEAR(u.per_cpu_busy_percent[1], 25.0, 1e-9);
  EXPECT_NEAR(*u.system_busy_percent, 50.0, 1e-9);
  // A process could not be read: what the others used is unknown.
  EXPECT_FALSE(u.other_cpu_percent.has_value());

  const auto j = to_json(u);
  EXPECT_EQ(j["processes"][0]["voluntary_context_switches"], 21);
  EXPECT_EQ(j["system"]["per_cpu"][1]["cpu"], 1);
  EXPECT_TRUE(j["system"]["other_processes_cpu_percent"].is_null());
}

TEST(ResourceMonitor, OtherProcessesLoadIsWhatTheGraphDidNotUse) {
  const double hz = static_cast<double>(::sysconf(_SC_CLK_TCK));
  const auto ticks = [hz](double s) { return static_cast<uint64_t>(s * hz); };
  FixtureProc proc;
  proc.process(7, 0, 0, 0, 0, 100, 0, 0, 0, 0);
  proc.stat(0, 0, 0, 0);
  ResourceMonitor monitor(proc.path(), {{7, "graph"}});
  monitor.begin(0);
  proc.process(7, 0, 0, ticks(0.5), 0, 100, 0, 0, 0, 0);
  proc.stat(ticks(1.0), ticks(0.0), ticks(0.7), ticks(0.3));  // 1.7 s busy in 1 s on 2 CPUs
  monitor.end(kSecond);
  const auto u = monitor.usage();
  ASSERT_TRUE(u.other_cpu_percent.has_value());
  EXPECT_NEAR(*u.other_cpu_percent, 120.0, 1e-9);
  EXPECT_NEAR(*u.system_busy_percent, 85.0, 1e-9);
}

TEST(ResourceMonitor, ThisProcessBurningCpu) {
  ResourceMonitor monitor("/proc", {{::getpid(), "self"}});
  const auto now = [] {
    return std::chrono::duration_cast<std::chrono::nanoseconds>(
               std::chrono::steady_clock::now().time_since_epoch())
        .count();
  };
  monitor.begin(now());
  const auto until = std::chrono::steady_clock::now() + std::chrono::milliseconds(300);
  std::atomic<uint64_t> spins = 0;
  while (std::chrono::steady_clock::now() < until) spins.fetch_add(1, std::memory_order_relaxed);
  monitor.end(now());
  const auto u = monitor.usage();
  ASSERT_TRUE(u.processes[0].measured) << u.processes[0].error;
  // A busy loop on a shared 2-core machine: at least some tens of percent, at most all cores.
  EXPECT_GT(u.processes[0].cpu_percent, 20.0);
  EXPECT_LT(u.processes[0].cpu_percent, 100.0 * std::thread::hardware_concurrency() + 20.0);
  EXPECT_GT(*u.processes[0].peak_rss_bytes, 1u << 20);
  EXPECT_EQ(u.per_cpu_busy_percent.size(), std::thread::hardware_concurrency());
  EXPECT_TRUE(u.system_busy_percent.has_value());
}

}  // namespace
}  // namespace robotperf::metrics
