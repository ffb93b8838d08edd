#include "robotperf/harness/backend_check.hpp"

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <mutex>
#include <stdexcept>

#include "robotperf/graph/executor.hpp"
#include "robotperf/graph/node.hpp"
#include "robotperf/msgs/known_types.hpp"
#include "robotperf/msgs/serialized_message.hpp"
#include "robotperf/plugin/registry.hpp"

namespace robotperf::harness {
namespace {

// The n-th frame's stamp in the reference: increasing, as the nodes' pairing wants.
int64_t stamp_of(std::size_t n) {
  return 1'000'000'000 + static_cast<int64_t>(n) * 1'000'000;
}

// The frame's message of a stream as the typed object the intra transport hands over (a bag's
// messages are CDR until decoded).
rmw::MessagePtr typed_copy(const DatasetStream& stream, const msgs::TypeSupport& typed,
                           std::size_t frame, int64_t stamp_ns) {
  const void* original = stream.messages[frame].get();
  if (!msgs::is_serialized_type_support(*stream.type))
    return stream.type->copy_with_stamp_ns(original, stamp_ns);
  std::shared_ptr<void> decoded = typed.create();
  typed.deserialize(static_cast<const msgs::SerializedMessage*>(original)->cdr, decoded.get());
  return typed.copy_with_stamp_ns(decoded.get(), stamp_ns);
}

const msgs::TypeSupport& known_type(const std::string& ros_type) {
  const msgs::TypeSupport* ts = nullptr;
  msgs::with_message_type(ros_type, [&]<class T>() { ts = &msgs::type_support<T>(); });
  if (ts == nullptr)
    throw std::invalid_argument("backend check: type " + ros_type + " is not compiled in");
  return *ts;
}

}  // namespace

std::optional<Agreement> compare_answers(const std::string& ros_type, const void* accelerated,
                                         const void* cpu) {
  const plugin::OutputComparisonEntry* comparison =
      plugin::registry().find_output_comparison(ros_type);
  if (comparison == nullptr) return std::nullopt;
  return comparison->compare(accelerated, cpu);
}

bool has_comparison(const std::string& ros_type) {
  return plugin::registry().find_output_comparison(ros_type) != nullptr;
}

void check_backend_available(const std::string& backend) {
  const plugin::BackendEntry* entry = plugin::registry().find_backend(backend);
  if (entry == nullptr || !entry->hooks.unavailable_reason) return;
  if (const std::string why = entry->hooks.unavailable_reason(); !why.empty())
    throw std::invalid_argument("--backend " + backend + ": " + why);
}

bool uses_other_backend(const BenchmarkSpec& spec) {
  return std::ranges::any_of(spec.nodes, [](const NodeSpec& n) { return n.backend != "cpu"; });
}

std::optional<BackendCheck> check_backend_answers(
    const BenchmarkSpec& spec, const Dataset& dataset,
    const std::vector<std::pair<uint64_t, rmw::MessagePtr>>& kept) {
  if (!uses_other_backend(spec) || kept.empty() || spec.inputs.empty() ||
      !has_comparison(spec.output.type)) {
    return std::nullopt;
  }
  BackendCheck check;
  for (const auto& n : spec.nodes) {
    if (n.backend != "cpu" && check.backend.find(n.backend) == std::string::npos)
      check.backend += (check.backend.empty() ? "" : ", ") + n.backend;
    // A kernel may come on a vendor's backend alone (a plug-in): nothing to compare it with.
    if (std::ranges::count(kernel_of(n).info.backends, "cpu") == 0) {
      throw std::runtime_error("node '" + n.name + "' (kernel " + n.kernel +
                               ") has no cpu backend, so there is no reference for its " +
                               n.backend + " answers");
    }
  }
  check.output_type = spec.output.type;

  graph::Context context(rmw::make_transport("intra"));
  graph::Node driver(context, "backend_check_driver");
  struct Input {
    std::shared_ptr<graph::GenericPublisher> publisher;
    const DatasetStream* stream;
    const msgs::TypeSupport* type;
  };
  std::vector<Input> inputs;
  for (const auto& in : spec.inputs) {
    const DatasetStream& stream = dataset.stream(in.stream);
    const msgs::TypeSupport& type = known_type(in.type);
    inputs.push_back({driver.create_generic_publisher(in.topic, type, in.qos), &stream, &type});
  }
  std::mutex mutex;
  std::condition_variable answered;
  rmw::MessagePtr answer;
  auto sink = std::make_shared<graph::Node>(context, "backend_check_sink");
  sink->create_generic_subscription(spec.output.topic, known_type(spec.output.type),
                                    spec.output.qos,
                                    [&](rmw::MessagePtr m, const graph::MessageInfo&) {
                                      {
                                        std::lock_guard lock(mutex);
                                        answer = std::move(m);
                                      }
                                      answered.notify_all();
                                    });
  graph::Executor executor(spec.executor_threads);
  for (NodeSpec n : spec.nodes) {
    n.backend = "cpu";
    n.device_resident_outputs.clear();  // the cpu's answers live on the host
    executor.add_node(make_kernel_node(n, context, spec.workload));
  }
  executor.add_node(sink);
  executor.start();

  auto in_order = kept;
  std::ranges::sort(in_order, {}, &std::pair<uint64_t, rmw::MessagePtr>::first);
  check.agreement = 1.0;
  std::string criterion;
  for (std::size_t n = 0; n < in_order.size(); ++n) {
    const auto& [id, output] = in_order[n];
    std::unique_lock lock(mutex);
    answer.reset();
    lock.unlock();
    for (const Input& in : inputs) {
      const auto frame = static_cast<std::size_t>(id % in.stream->messages.size());
      in.publisher->publish(typed_copy(*in.stream, *in.type, frame, stamp_of(n)));
    }
    lock.lock();
    if (!answered.wait_for(lock, std::chrono::seconds(10), [&] { return answer != nullptr; })) {
      check.reasons.push_back("the nodes on cpu gave no answer to message " + std::to_string(id) +
                              " within 10 s");
      break;
    }
    const auto a = compare_answers(spec.output.type, output.get(), answer.get());
    ++check.compared;
    check.agreement = std::min(check.agreement, a->share);
    check.required = a->required;
    check.criterion = a->criterion;
  }
  executor.stop();
  check.passed = check.reasons.empty() && check.compared > 0 && check.agreement >= check.required;
  if (check.reasons.empty() && !check.passed) {
    check.reasons.push_back(check.backend + " drifts from cpu: " + check.criterion + " " +
                            std::to_string(100.0 * check.agreement) + " % in the worst output, " +
                            std::to_string(100.0 * check.required) + " % required");
  }
  return check;
}

}  // namespace robotperf::harness
