#include "grey_box.hpp"

#include <unistd.h>

#include <algorithm>
#include <stdexcept>

#include "robotperf/metrics/delivery_validity.hpp"
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
                                   RunResult& result)
    : output_topic_(spec.output.topic),
      min_samples_(spec.min_samples),
      max_loss_percent_(spec.max_loss_percent) {
  for (const auto& in : spec.inputs) input_topics_.push_back(in.topic);
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
  // A graph whose outputs carry stamps of their own matched none of them by ID: the trace links
  // them to the inputs through the graph instead (docs/design.md §3.13).
  if (a.matched == 0 && a.unknown > 0) {
    if (auto path = path_to_output(a)) {
      ao.path = std::move(*path);
      tracing::TraceAnalysis along = tracing::analyze_trace(r.trace_dir, ao);
      if (along.path && along.path->reached > 0) {
        measure_along_path(r, *along.path);
        a = std::move(along);
      }
    }
  }
  if (r.outputs_restamped) {
    // The trace's own defects still count; what its ID matching said of the outputs does not,
    // the path's counts do.
    const auto by_id = metrics::delivery_invalid_reasons(
        {a.matched, a.duplicates, a.unknown, a.loss_percent}, min_samples_, max_loss_percent_);
    std::erase_if(a.invalid_reasons, [&](const std::string& why) {
      return std::ranges::find(by_id, why) != by_id.end();
    });
    for (auto& why : metrics::delivery_invalid_reasons({r.matched, r.duplicates, 0, r.loss_percent},
                                                       min_samples_, max_loss_percent_))
      a.invalid_reasons.push_back(std::move(why));
  }
  r.invalid_reasons.insert(r.invalid_reasons.end(), a.invalid_reasons.begin(),
                           a.invalid_reasons.end());
  r.valid = r.invalid_reasons.empty();
  r.grey = std::move(a);
}

std::optional<std::vector<std::string>> GreyBoxRecording::path_to_output(
    const tracing::TraceAnalysis& a) const {
  const tracing::PathSearch search = tracing::find_paths(a.graph);
  const std::vector<std::string>* best = nullptr;
  for (const auto& p : search.paths) {
    if (p.cut || p.topics.back() != output_topic_) continue;
    if (std::ranges::find(input_topics_, p.topics.front()) == input_topics_.end()) continue;
    if (best == nullptr || p.topics.size() < best->size()) best = &p.topics;
  }
  if (best == nullptr) return std::nullopt;
  return *best;
}

void GreyBoxRecording::measure_along_path(RunResult& r, const tracing::PathLatency& p) const {
  r.outputs_restamped = true;
  r.measured = p.sources;
  r.matched = p.reached;
  r.lost = p.sources - p.reached;
  r.loss_percent =
      p.sources ? 100.0 * static_cast<double>(r.lost) / static_cast<double>(p.sources) : 0.0;
  r.unknown = 0;
  // From the Playback's publish to the Monitor's take: the path has no schedule of its own.
  r.latency_from_sent = p.end_to_end;
  r.latency_from_scheduled = p.end_to_end;
  std::vector<metrics::TimedEvent> arrivals;
  for (const auto& instance : p.instances) arrivals.push_back({instance.end, instance.end});
  r.throughput_hz = metrics::event_rate_hz(arrivals);
  if (!r.outputs.empty()) {
    // The run's own output, as the path measured it; its jitter from the arrivals' intervals.
    OutputFigures& out = r.outputs.front();
    out.matched = r.matched;
    out.lost = r.lost;
    out.loss_percent = r.loss_percent;
    out.latency_from_scheduled = out.latency_from_sent = p.end_to_end;
    out.throughput_hz = r.throughput_hz;
    std::vector<int64_t> ends;
    for (const auto& instance : p.instances) ends.push_back(instance.end);
    const metrics::OutputJitter j = metrics::output_jitter(std::move(ends), out.period_ns);
    out.interval = j.interval;
    out.jitter = j.jitter;
  }
  std::string path;
  for (const auto& t : p.topics) path += (path.empty() ? "" : " -> ") + t;
  r.warnings.push_back(
      {"restamped_output",
       "the outputs carry header stamps of their own (no input's): latency is measured along the "
       "path " +
           path +
           " from the trace, from the Playback's publish to the Monitor's take (docs/"
           "design.md §3.13), not from the scheduled send"});
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
