#include "node_reference.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <thread>

#include "robotperf/msgs/known_types.hpp"
#include "robotperf/rmw/transport.hpp"

namespace robotperf::bench {

namespace {

// The n-th frame's ID as a header stamp: any increasing value serves; the nodes pair inputs by
// it and drop what is older than what they paired.
int64_t stamp_of(std::size_t n) {
  return 1'000'000'000 + static_cast<int64_t>(n) * 1'000'000;
}

}  // namespace

NodeReference::NodeReference(const harness::BenchmarkSpec& spec, const harness::Dataset& dataset)
    : dataset_(dataset),
      context_(std::make_unique<graph::Context>(rmw::make_transport("intra"))),
      driver_(std::make_unique<graph::Node>(*context_, "reference_driver")),
      executor_(std::make_unique<graph::Executor>(spec.executor_threads)) {
  if (spec.inputs.empty() || spec.nodes.empty())
    throw std::invalid_argument(spec.id + " has no inputs or no nodes of robotperf's own");
  for (const auto& in : spec.inputs) {
    const harness::DatasetStream& stream = dataset.stream(in.stream);
    if (stream.messages.empty() || stream.type == nullptr)
      throw std::invalid_argument("dataset stream " + in.stream + " has no messages");
    inputs_.push_back({driver_->create_generic_publisher(in.topic, *stream.type, in.qos), &stream});
  }
  // The probe hears the frame's first input; the executor runs it before the kernel nodes.
  auto probe = std::make_shared<graph::Node>(*context_, "reference_probe");
  probe->create_generic_subscription(spec.inputs.front().topic, *inputs_.front().stream->type,
                                     spec.inputs.front().qos,
                                     [this](rmw::MessagePtr, const graph::MessageInfo&) {
                                       std::lock_guard lock(mutex_);
                                       if (first_callback_ == Clock::time_point{})
                                         first_callback_ = Clock::now();
                                     });
  executor_->add_node(probe);
  for (const auto& n : spec.nodes)
    executor_->add_node(harness::make_kernel_node(n, *context_, spec.workload));
  const msgs::TypeSupport* output = nullptr;
  msgs::with_message_type(spec.output.type, [&]<class T>() { output = &msgs::type_support<T>(); });
  if (output == nullptr)
    throw std::invalid_argument("output type " + spec.output.type + " is not a known type");
  auto sink = std::make_shared<graph::Node>(*context_, "reference_sink");
  sink->create_generic_subscription(
      spec.output.topic, *output, spec.output.qos,
      [this](rmw::MessagePtr, const graph::MessageInfo&) {
        const auto now = Clock::now();
        {
          std::lock_guard lock(mutex_);
          // An answer to a frame given up on: not this frame's.
          if (first_callback_ == Clock::time_point{}) return;
          took_ms_.push_back(
              std::chrono::duration<double, std::milli>(now - first_callback_).count());
          first_callback_ = {};
        }
        answered_.notify_all();
      });
  executor_->add_node(sink);
  executor_->start();
}

NodeReference::~NodeReference() {
  executor_->stop();
}

std::vector<double> NodeReference::run_paced(Clock::time_point first, Clock::duration period,
                                             Clock::duration lead, std::size_t count) {
  std::vector<double> took;
  std::vector<rmw::MessagePtr> frame;
  for (std::size_t k = 0; k < count; ++k) {
    const auto due = first + static_cast<long>(k) * period;
    std::this_thread::sleep_until(due - lead);
    frame.clear();
    for (const auto& in : inputs_) {
      const auto& messages = in.stream->messages;
      frame.push_back(in.stream->type->copy_with_stamp_ns(messages[k % messages.size()].get(),
                                                          stamp_of(sent_)));
    }
    ++sent_;
    std::unique_lock lock(mutex_);
    const std::size_t before = took_ms_.size();
    first_callback_ = {};
    lock.unlock();
    std::this_thread::sleep_until(due);
    for (std::size_t i = 0; i < inputs_.size(); ++i)
      inputs_[i].publisher->publish(std::move(frame[i]));
    lock.lock();
    if (answered_.wait_for(lock, std::chrono::seconds(1),
                           [&] { return took_ms_.size() > before; })) {
      took.push_back(took_ms_.back());
    } else {
      took.push_back(NAN);
    }
  }
  return took;
}

harness::RunResult NodeReference::run_beside(
    harness::RunOptions options,
    const std::function<harness::RunResult(const harness::RunOptions&)>& run_graph,
    std::vector<double>& reference_ms) {
  if (!options.load.rate_hz || !options.load.count || !options.load.warmup)
    throw std::invalid_argument("a round beside the graph needs its rate, count and warm-up");
  const std::size_t count = *options.load.count, warmup = *options.load.warmup;
  // The graph's first send, as a steady-clock count; -1 when the graph ended without one.
  std::atomic<Clock::rep> first_send{0};
  options.progress = [&](std::size_t sent, std::size_t, std::size_t) {
    if (sent == 1 && first_send == 0) first_send = Clock::now().time_since_epoch().count();
  };
  const auto period = std::chrono::duration_cast<Clock::duration>(
      std::chrono::duration<double>(1.0 / *options.load.rate_hz));
  std::thread beside([&] {
    while (first_send == 0) std::this_thread::sleep_for(std::chrono::milliseconds(1));
    if (first_send < 0) return;
    const Clock::time_point first{Clock::duration(first_send.load())};
    const auto took = run_paced(first + period / 2, period, std::chrono::milliseconds(2), count);
    // A frame whose answer never came (NaN) has no time: the graph's side counts it as lost.
    for (std::size_t k = warmup; k < took.size(); ++k) {
      if (std::isfinite(took[k])) reference_ms.push_back(took[k]);
    }
  });
  auto give_up = [&] {
    Clock::rep none = 0;
    first_send.compare_exchange_strong(none, -1);
    beside.join();
  };
  try {
    harness::RunResult r = run_graph(options);
    give_up();
    return r;
  } catch (...) {
    give_up();
    throw;
  }
}

OverheadSamples measure_overhead_round(const harness::BenchmarkSpec& spec,
                                       const harness::Dataset& dataset,
                                       const harness::RunOptions& options,
                                       harness::RunResult& graph_result) {
  NodeReference reference(spec, dataset);
  OverheadSamples samples;
  graph_result = reference.run_beside(
      options, [&](const harness::RunOptions& with) { return harness::run_benchmark(spec, with); },
      samples.reference_ms);
  const std::size_t measured = graph_result.count - graph_result.warmup;
  if (graph_result.matched < measured)
    std::fprintf(stderr, "%s: only %zu of %zu outputs matched\n", spec.id.c_str(),
                 graph_result.matched, measured);
  for (const auto& rec : graph_result.records) {
    if (!rec.warmup && rec.received_ns >= 0)
      samples.graph_ms.push_back(static_cast<double>(rec.received_ns - rec.sent_ns) / 1e6);
  }
  return samples;
}

}  // namespace robotperf::bench
