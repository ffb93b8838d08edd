#include "grey_box.hpp"

#include <unistd.h>

#include <stdexcept>

#include "robotperf/tracing/tracepoints.hpp"

namespace robotperf::harness {
namespace {

// Events one frame causes: every port of the graph is one side of a topic
// (publish: 4 events, take and callback: 7), kernels add 2 (8 on a device: its upload, compute
// and download stages), input and output 2.
double events_per_frame(const BenchmarkSpec& spec) {
  std::size_t ports = spec.inputs.size() + 1;
  double kernels = 0;
  for (const auto& n : spec.nodes) {
    ports += n.topics.size();
    kernels += n.backend == "cpu" ? 2.0 : 8.0;
  }
  return 6.0 * static_cast<double>(ports) + kernels + 4.0;
}

// Events of the control loops, per second, whatever the message rate (each kernel with a loop
// says how many one cycle emits).
double control_loop_events_per_second(const BenchmarkSpec& spec) {
  double events = 0;
  for (const auto& n : spec.nodes) {
    const auto& loop = kernel_of(n).info.control_loop;
    if (!loop) continue;
    // Parameters were checked when the package was loaded: the rate converts.
    const plugin::Parameters p(kernel_of(n).info.parameters, n.parameters, n.name);
    events += loop->trace_events_per_cycle * p.get_double(loop->rate_parameter);
  }
  return events;
}

}  // namespace

GreyBoxRecording::GreyBoxRecording(const BenchmarkSpec& spec, const RunOptions& options,
                                   RunResult& result) {
  if (options.tracing.trace_dir.empty())
    throw std::invalid_argument("grey-box mode needs a trace folder");
  tracing::SessionOptions s;
  s.output_dir = options.tracing.trace_dir;
  s.name_hint = spec.id;
  s.subbuf_bytes = options.tracing.subbuf_bytes != 0
                       ? options.tracing.subbuf_bytes
                       : tracing::subbuffer_bytes_for(result.rate_hz * events_per_frame(spec) +
                                                      control_loop_events_per_second(spec));
  // Processes of the graph that are spawned later (per-node, an external graph's `launch:`)
  // start tracing before they could be added to a tracker, so only a single-process run of
  // robotperf's own nodes is recorded alone.
  if (options.processes.layout == ProcessLayout::kSingle && spec.launch.empty())
    s.only_processes = {getpid()};
  session_ = std::make_unique<tracing::RecordingSession>(s);
  result.trace_dir = session_->output_dir();
  result.trace_subbuf_bytes = session_->subbuf_bytes();
}

void GreyBoxRecording::finish(RunResult& r) {
  session_->stop();
  tracing::AnalyzeOptions ao;
  ao.run_pid = getpid();
  for (const auto& n : r.nodes) {
    if (n.pid > 0) ao.extra_processes.insert(n.pid);
  }
  for (const auto& l : r.launched) {
    if (l.pid > 0) ao.extra_processes.insert(l.pid);
  }
  tracing::TraceAnalysis a = tracing::analyze_trace(r.trace_dir, ao);

  r.sent = a.sent;
  r.measured = a.measured;
  r.matched = a.matched;
  r.lost = a.lost;
  r.loss_percent = a.loss_percent;
  r.duplicates = a.duplicates;
  r.repeats = a.repeats;
  r.unknown = a.unknown;
  r.unobserved = a.unobserved;
  r.latency_from_scheduled = a.latency_from_scheduled;
  r.latency_from_sent = a.latency_from_sent;
  r.send_lateness = a.send_lateness;
  r.throughput_hz = a.throughput_hz;
  r.offered_rate_hz = a.offered_rate_hz;
  r.window_s = a.window_s;
  r.records.clear();
  for (const auto& m : a.messages) {
    r.records.push_back({m.index, m.scheduled_ns, m.sent_ns, m.received_ns, m.warmup});
  }
  r.invalid_reasons.clear();
  for (const auto& e : r.errors) r.invalid_reasons.push_back("run ended early: " + e);
  r.invalid_reasons.insert(r.invalid_reasons.end(), a.invalid_reasons.begin(),
                           a.invalid_reasons.end());
  r.valid = r.invalid_reasons.empty();
  r.grey = std::move(a);
}

void trace_run_begin(const BenchmarkSpec& spec, const RunResult& r, int64_t period_ns) {
  lttng_ust_tracepoint(robotperf, run_begin, spec.id.c_str(), r.rmw.c_str(), r.count, r.warmup,
                       period_ns, spec.min_samples, spec.max_loss_percent,
                       spec.output.state ? 1 : 0);
}

void trace_run_end(std::size_t sent) {
  lttng_ust_tracepoint(robotperf, run_end, sent);
}

void trace_run_join() {
  lttng_ust_tracepoint(robotperf, run_join, static_cast<int>(getppid()));
}

}  // namespace robotperf::harness
