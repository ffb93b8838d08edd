// Private to the harness: the loop metrics of kernels that run a control loop, computed from a
// loop's report in the process that ran it and, for per-node runs, shipped to the runner as JSON
// on the child's stats line (the command writes travel raw: only the runner knows the messages'
// scheduled send times). CLOCK_MONOTONIC is system-wide, so the times compare across processes.
#pragma once

#include <cstddef>
#include <nlohmann/json.hpp>
#include <vector>

#include "black_box.hpp"
#include "robotperf/harness/run.hpp"
#include "robotperf/plugin/control_loop.hpp"

namespace robotperf::harness {

// Everything of the loop's result but command_to_write.
ControlLoopResult control_loop_timing(const plugin::LoopReport& loop);

// Hardware written with a measured command minus that command's scheduled send.
metrics::SampleStats command_to_write(const std::vector<plugin::CommandWrite>& writes,
                                      const MessageIds& ids,
                                      const std::vector<MessageRecord>& records,
                                      std::size_t warmup);

// The child's side: the timing (nanoseconds) and the raw command writes.
nlohmann::json control_loop_to_wire(const plugin::LoopReport& loop);

// The runner's side; throws nlohmann::json::exception on a malformed message. The command ->
// write latency is left empty when `wire` says ("same_machine": false) the loop ran on another
// machine, whose monotonic clock is not the runner's.
ControlLoopResult control_loop_from_wire(const nlohmann::json& wire, const MessageIds& ids,
                                         const std::vector<MessageRecord>& records,
                                         std::size_t warmup);

}  // namespace robotperf::harness
