#include "robotperf/harness/scheduling.hpp"

#include <gtest/gtest.h>
#include <sched.h>

#include <thread>

namespace robotperf::harness {
namespace {

TEST(Scheduling, CpuListsRoundTrip) {
  EXPECT_EQ(parse_cpu_list("0-3,6"), (std::vector<unsigned>{0, 1, 2, 3, 6}));
  EXPECT_EQ(parse_cpu_list("5,1,1-2"), (std::vector<unsigned>{1, 2, 5}));
  EXPECT_EQ(format_cpu_list({0, 1, 2, 3, 6, 8, 9}), "0-3,6,8-9");
  EXPECT_EQ(format_cpu_list(parse_cpu_list("7")), "7");
  for (const char* bad : {"", "a", "1-", "3-1", "1,,2", "-2", "99999999"}) {
    EXPECT_THROW(parse_cpu_list(bad), std::invalid_argument) << bad;
  }
  SchedulingOptions o;
  o.cpus = {2, 3};
  o.rt_priority = 10;
  o.lock_memory = true;
  EXPECT_EQ(o.node_arguments(),
            (std::vector<std::string>{"--cpus", "2-3", "--rt-priority", "10", "--mlock"}));
  EXPECT_TRUE(SchedulingOptions{}.node_arguments().empty());
}

unsigned allowed_cpus() {
  cpu_set_t set;
  sched_getaffinity(0, sizeof set, &set);
  return static_cast<unsigned>(CPU_COUNT(&set));
}

TEST(Scheduling, PinningCoversNewThreadsAndIsUndone) {
  const unsigned before = allowed_cpus();
  {
    SchedulingOptions o;
    o.cpus = {0};
    ScopedScheduling pinned(o);
    EXPECT_EQ(allowed_cpus(), 1u);
    unsigned in_thread = 0;
    std::thread([&] { in_thread = allowed_cpus(); }).join();
    EXPECT_EQ(in_thread, 1u);
  }
  EXPECT_EQ(allowed_cpus(), before);
}

TEST(Scheduling, RefusalSaysWhatToDo) {
  SchedulingOptions o;
  o.cpus = {CPU_SETSIZE - 1};  // no such CPU
  try {
    ScopedScheduling pinned(o);
    FAIL() << "pinning to a missing CPU succeeded";
  } catch (const std::invalid_argument& e) {
    // Checked against the CPUs this process may use before asking the kernel.
    EXPECT_NE(std::string(e.what()).find("not available to this process (it may run on"),
              std::string::npos)
        << e.what();
  }
  o.cpus.clear();
  o.rt_priority = 100;
  EXPECT_THROW(ScopedScheduling{o}, std::invalid_argument);
}

}  // namespace
}  // namespace robotperf::harness
