#include "robotperf/harness/run.hpp"

#include <signal.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <nlohmann/json.hpp>
#include <thread>

#include "control_loop.hpp"
#include "graph_connection.hpp"
#include "grey_box.hpp"
#include "node_processes.hpp"
#include "robotperf/graph/executor.hpp"
#include "robotperf/plugin/control_loop.hpp"
#include "run_plan.hpp"
#include "run_stages.hpp"

namespace robotperf::harness {
namespace {

// How often a node process looks for a stuck callback.
constexpr int64_t kWatchPeriodNs = 100'000'000;
// The exit status of a node process whose watchdog found a callback stuck.
constexpr int kNodeHungExit = 5;

}  // namespace

std::string interrupted_by(int signal_number) {
  return std::string("interrupted by SIG") + sigabbrev_np(signal_number);
}

std::string to_string(RunStage stage) {
  switch (stage) {
    case RunStage::kPlan:
      return "plan";
    case RunStage::kPrepare:
      return "prepare";
    case RunStage::kStartGraph:
      return "start_graph";
    case RunStage::kConnect:
      return "connect";
    case RunStage::kMeasure:
      return "measure";
    case RunStage::kDrain:
      return "drain";
    case RunStage::kStopGraph:
      return "stop_graph";
    case RunStage::kSummarise:
      return "summarise";
    case RunStage::kCheck:
      return "check";
  }
  return "unknown";
}

std::vector<double> scheduled_latencies_ms(const RunResult& r) {
  std::vector<double> out;
  out.reserve(r.records.size());
  for (const auto& rec : r.records) {
    if (!rec.warmup && rec.received_ns >= 0)
      out.push_back(static_cast<double>(rec.received_ns - rec.scheduled_ns) / 1e6);
  }
  return out;
}

void move_trace(RunResult& r, const std::filesystem::path& to) {
  const std::string from = r.trace_dir.string();
  std::filesystem::rename(r.trace_dir, to);
  r.trace_dir = to;
  const std::string now = to.string();
  auto rebase = [&](std::vector<std::string>& lines) {
    for (std::string& line : lines) {
      for (auto at = line.find(from); at != std::string::npos;
           at = line.find(from, at + now.size()))
        line.replace(at, from.size(), now);
    }
  };
  rebase(r.invalid_reasons);
  rebase(r.errors);
  if (r.grey) {
    rebase(r.grey->traces);
    rebase(r.grey->packet_defects);
    rebase(r.grey->unavailable);
    rebase(r.grey->invalid_reasons);
  }
}

nlohmann::json device_to_json(const plugin::DeviceInfo& device) {
  return {{"name", device.name},
          {"vendor", device.vendor},
          {"driver", device.driver},
          {"runtime", device.runtime},
          {"memory_bytes", device.memory_bytes}};
}

plugin::DeviceInfo device_from_json(const nlohmann::json& j) {
  return {j.value("name", ""), j.value("vendor", ""), j.value("driver", ""), j.value("runtime", ""),
          j.value("memory_bytes", uint64_t{0})};
}

// The stages in their order (run_stages.hpp); each object declared here owns what its stage
// acquired, so that leaving at any point releases exactly that, in reverse order.
RunResult run_benchmark(const BenchmarkSpec& package_spec, const RunOptions& options) {
  const auto begin = [&options](RunStage stage) {
    if (options.on_stage) options.on_stage(stage);
  };
  begin(RunStage::kPlan);
  RunPlan plan = plan_run(package_spec, options);
  RunResult r = std::move(plan.result);

  begin(RunStage::kPrepare);
  RunEnvironment environment(plan, options, r);
  Instruments instruments(plan, options, environment, r);

  begin(RunStage::kStartGraph);
  GraphUnderTest graph(plan, options, environment, instruments, r);

  begin(RunStage::kConnect);
  connect_graph(plan, options, environment, graph, r);
  MeasurementWindow window(options, plan.spec(), graph);
  check_before_timing(plan, options, environment, window, r);
  RunWatch watch(options, instruments, graph, r);

  begin(RunStage::kMeasure);
  warm_up_and_measure(plan, options, instruments, window, watch, r);

  begin(RunStage::kDrain);
  const Monitor::Tally tally = drain(plan, options, instruments, window, watch, r);

  begin(RunStage::kStopGraph);
  stop_graph(plan, environment, instruments, graph, watch, r);

  begin(RunStage::kSummarise);
  summarise_run(plan, options, environment, tally, instruments.more_tallies, r);

  begin(RunStage::kCheck);
  check_outputs(plan, instruments, tally, r);
  return r;
}

int run_node_process(const BenchmarkSpec& spec, const std::string& node_name,
                     const std::string& rmw, int domain_id, const SchedulingOptions& scheduling,
                     double callback_timeout_s, const std::string& run_token,
                     const std::filesystem::path& keystore, rmw::RosDistro ros_distro) {
  // Ctrl-C (or Ctrl-\ or a dropped terminal) reaches the whole process group: the runner
  // stops us when it is done.
  for (const int s : {SIGINT, SIGQUIT, SIGHUP}) signal(s, SIG_IGN);
  const NodeSpec* node_spec = spec.find_node(node_name);
  if (node_spec == nullptr) {
    std::cerr << "robotperf node: benchmark " << spec.id << " has no node '" << node_name << "'\n";
    return 2;
  }
  // Before the transport and executor start their threads, so that they all inherit it.
  std::optional<ScopedScheduling> scheduled;
  try {
    scheduled.emplace(scheduling);
  } catch (const std::exception& e) {
    std::cerr << "robotperf node " << node_name << ": " << e.what() << "\n";
    return 2;
  }
  // First, so that the runner knows where we run even if we fail to start.
  std::cout << "host " << this_host_identity().dump() << std::endl;
  rmw::TransportOptions t;
  t.domain_id = domain_id;
  if (!run_token.empty()) t.user_data = run_user_data(run_token);
  if (!keystore.empty()) t.security = rmw::enclave_files(keystore);
  t.ros_distro = ros_distro;
  graph::Context context(rmw::make_transport(rmw, t));
  trace_run_join();
  auto node = make_kernel_node(*node_spec, context, spec.workload);
  if (const auto device = device_of(*node, *node_spec))
    std::cout << "device " << device_to_json(*device).dump() << std::endl;
  graph::Executor executor(spec.executor_threads);
  executor.add_node(node);

  // The runner closes our stdin to stop us; a dead runner does the same.
  std::atomic<bool> stdin_closed = false;
  std::thread watcher([&] {
    char buf[256];
    while (std::cin.read(buf, sizeof buf) || std::cin.gcount() > 0) {
    }
    stdin_closed = true;
    executor.cancel();
  });

  // A callback stuck past the timeout: tell the runner, then end, since it will not return.
  std::atomic<bool> done = false;
  const auto limit_ns = static_cast<int64_t>(callback_timeout_s * 1e9);
  std::thread watchdog([&] {
    while (!done) {
      std::this_thread::sleep_for(std::chrono::nanoseconds(kWatchPeriodNs));
      if (auto stuck = executor.running_longer_than(limit_ns, rmw::steady_now_ns())) {
        std::cout << "hung its callback has run for "
                  << number_text(static_cast<double>(stuck->running_ns) * 1e-9)
                  << " s, longer than the callback timeout (" << number_text(callback_timeout_s)
                  << " s, --callback-timeout)" << std::endl;
        std::_Exit(kNodeHungExit);
      }
    }
  });

  int code = 0;
  try {
    // Matching happens in the transport's threads; messages that arrive
    // before spin() wait in the subscriptions' queues. The runner's --connect-timeout bounds the
    // wait: when it gives up, it closes our stdin.
    if (wait_connected({node}, wiring_of(spec), INT64_MAX, [&] { return stdin_closed.load(); })) {
      std::cout << "ready" << std::endl;
      executor.spin();  // until the watcher cancels it, or a callback throws
    }
  } catch (const std::exception& e) {
    std::cerr << "robotperf node " << node_name << ": " << e.what() << "\n";
    // The runner records it with the node's exit status (one line on the wire).
    std::string what = e.what();
    std::ranges::replace(what, '\n', ' ');
    std::cout << "error " << what << std::endl;
    code = 3;
  }
  done = true;
  watchdog.join();
  if (!stdin_closed) {
    // Failed on our own: leave without waiting for the runner.
    std::cout.flush();
    std::_Exit(code);
  }
  watcher.join();
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  auto seconds = [](timeval tv) { return static_cast<double>(tv.tv_sec) + tv.tv_usec * 1e-6; };
  nlohmann::json stats = {{"cpu_user_s", seconds(usage.ru_utime)},
                          {"cpu_system_s", seconds(usage.ru_stime)},
                          {"counters", nlohmann::json::object()}};
  // The loop's metrics are read here, where the loop ran, and go to the runner with the stats;
  // stopping the loop first, so that the counters below are not read while it runs.
  if (auto* loop = dynamic_cast<plugin::ControlLoopSource*>(node.get()))
    stats["control_loop"] = control_loop_to_wire(loop->stop_and_report());
  if (const auto* c = dynamic_cast<const plugin::NodeCounters*>(node.get())) {
    for (const auto& [name, value] : c->counters()) stats["counters"][name] = value;
  }
  std::cout << "stats " << stats.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace)
            << std::endl;
  return code;
}

}  // namespace robotperf::harness
