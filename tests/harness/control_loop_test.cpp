// A control loop's report from a node process to the runner, and the command -> write latency
// the runner computes from it.
#include "control_loop.hpp"

#include <gtest/gtest.h>

#include <vector>

#include "run_isolation.hpp"

namespace robotperf::harness {
namespace {

// A loop that wrote command 3, 2 ms after its scheduled send, and the runner's records.
struct Fixture {
  MessageIds ids{1'000'000'000, 10'000'000, 5};
  std::vector<MessageRecord> records;
  plugin::LoopReport loop;
  Fixture() {
    for (uint64_t k = 0; k < ids.count; ++k)
      records.push_back({k, 5'000'000'000 + static_cast<int64_t>(k) * 10'000'000, 0, -1, false});
    loop.name = "controller_manager";
    loop.update_rate_hz = 100;
    loop.writes.push_back({ids.stamp_ns(3), records[3].scheduled_ns + 2'000'000});
  }
};

TEST(ControlLoopWire, CommandToWriteOnTheRunnersMachine) {
  const Fixture f;
  const auto c = control_loop_from_wire(control_loop_to_wire(f.loop), f.ids, f.records, 1);
  EXPECT_EQ(c.node, "controller_manager");
  ASSERT_EQ(c.command_to_write.count, 1u);
  EXPECT_DOUBLE_EQ(c.command_to_write.p50, 2'000'000.0);
}

// Another machine's CLOCK_MONOTONIC counts from its own boot: its writes against the runner's
// send times would be hours or negative, so the latency is left out.
TEST(ControlLoopWire, NoCommandToWriteFromAnotherMachine) {
  const Fixture f;
  auto wire = control_loop_to_wire(f.loop);
  wire["same_machine"] = false;
  const auto c = control_loop_from_wire(wire, f.ids, f.records, 1);
  EXPECT_EQ(c.command_to_write.count, 0u);
  EXPECT_EQ(c.node, "controller_manager");  // the loop's own timing is still there
}

}  // namespace
}  // namespace robotperf::harness
