// `robotperf run ID`: its options and what it runs (run_options.cpp builds the harness's options,
// run_drivers.cpp runs and writes).
#include "run.hpp"

#include <stdexcept>

#include "../interrupts.hpp"
#include "commands.hpp"

namespace robotperf::cli {

namespace {

class RunCommand : public Command {
 public:
  CLI::App* declare(CLI::App& app) override {
    command_ = app.add_subcommand("run", "run a benchmark and print its summary");
    declare_input();
    declare_peak_search();
    declare_series();
    declare_sending();
    declare_graph();
    declare_output();
    command_->footer(
        "Examples: robotperf run a1 --rate 30\n"
        "          robotperf run a5 --repeat 5 --rmw fastdds --processes per-node");
    return command_;
  }

  int run(const Context& context) override {
    // Before any resource is made (the --netns link, the domain --domain auto reserves, a
    // trace session): from here on a signal ends the run through its clean-up.
    const InterruptHandling interrupts;
    auto spec = harness::find_benchmark(context.roots, args_.id);
    apply_workload(spec, args_);
    std::optional<harness::NetworkLink> link;
    const harness::RunOptions options = run_options(spec, args_, context, link);
    if (options.tracing.mode == harness::RunMode::kGrey) remove_grey_leftovers(args_);
    if (args_.find_peak) return run_peak_search(spec, args_, options);
    if (args_.sweep) {
      if (args_.repeat > 1)
        throw std::invalid_argument("--sweep runs once per value: not with --repeat");
      return run_sweep(spec, args_, options);
    }
    if (args_.repeat > 1) return run_series(spec, args_, options);
    return run_once(spec, args_, options);
  }

 private:
  // The benchmark, its rate and the input a bag gives.
  void declare_input() {
    command_->add_option("id", args_.id, "benchmark id or name, e.g. a1")->required();
    command_
        ->add_option("--rate", args_.rate,
                     "input rate in Hz (30, 30Hz, 1.5kHz; default: the benchmark's), or 'bag': "
                     "the bag's own timeline")
        ->transform(hertz_with_unit({"bag"}));
    command_
        ->add_option("--update-rate", args_.update_rate,
                     "control benchmarks: the controller manager's loop rate in Hz (default: "
                     "the graph's update_rate), e.g. 1kHz to stress the loop")
        ->transform(hertz_with_unit());
    command_
        ->add_option("--callback-timeout", args_.callback_timeout_s,
                     "seconds a node's callback may run before the run ends with the node named "
                     "as hung (default 30)")
        ->transform(seconds_with_unit())
        ->check(kPositive);
    command_
        ->add_option("--rate-scale", args_.rate_scale,
                     "with --rate bag: play this many times faster")
        ->check(kPositive);
    auto* dataset =
        command_->add_option("--dataset", args_.dataset,
                             "replay this rosbag2 bag (directory, .db3 or .mcap) as the input");
    command_
        ->add_option("--remap", args_.remaps,
                     "bag topic onto a benchmark input: from:=to (repeatable)")
        ->needs(dataset);
    command_->add_option("--window", args_.window, "only the bag's messages in START:END seconds")
        ->needs(dataset);
  }

  void declare_peak_search() {
    find_peak_ = command_->add_flag(
        "--find-peak", args_.find_peak,
        "search for the highest input rate the graph sustains (each step a full run of "
        "--duration seconds, default 5, from --rate or the benchmark's rate upwards)");
    command_
        ->add_option("--loss-bound", args_.loss_bound,
                     "with --find-peak: the most loss (%) a sustained rate may have (default: the "
                     "benchmark's max_loss_percent)")
        ->needs(find_peak_);
    command_
        ->add_option("--latency-bound", args_.latency_bound,
                     "with --find-peak: the latency (ms) the --latency-percentile must stay within")
        ->needs(find_peak_);
    command_
        ->add_option("--latency-percentile", args_.latency_percentile,
                     "with --latency-bound: which percentile of the latency (default 99)")
        ->needs(find_peak_);
    command_
        ->add_option("--rate-range", args_.rate_range,
                     "with --find-peak: LO:HI, the rates searched (default: from the start rate "
                     "to 1 MHz)")
        ->needs(find_peak_);
    command_
        ->add_option("--peak-resolution", args_.peak_resolution,
                     "with --find-peak: stop bisecting when the failing rate is within this many "
                     "percent of the sustained one (default 5)")
        ->needs(find_peak_);
  }

  // Several runs: --repeat and --sweep, and the workload they may vary.
  void declare_series() {
    command_
        ->add_option("--repeat", args_.repeat,
                     "run N times, each with a fresh graph, and summarise the series: the median "
                     "of each headline figure with its 95 % interval and the run-to-run spread")
        ->transform(whole_number(1, 10000));
    command_
        ->add_option("--repeat-pause", args_.repeat_pause, "with --repeat: seconds between runs")
        ->transform(seconds_with_unit())
        ->check(number_between(0.0, 3600.0));
    command_->add_option("--workload", args_.workload,
                         "KEY=VALUE: a workload parameter of the benchmark's dataset, over "
                         "benchmark.yaml's (repeatable; `list datasets` names them)");
    auto* sweep = command_->add_option(
        "--sweep", args_.sweep,
        "KEY=V1,V2,...: one run per value of a workload parameter, then the values side by side "
        "(e.g. payload_bytes=64,1024,65536,1048576,4194304 for n1 and n2)");
    find_peak_->excludes(sweep);
  }

  // How many messages are sent, when, and how the outputs are awaited.
  void declare_sending() {
    command_->add_option("--arrival", args_.arrival,
                         "when messages are sent at the rate: fixed (default), poisson (random "
                         "intervals of mean 1/rate) or burst:N (N back to back every N/rate)");
    command_
        ->add_option("--arrival-seed", args_.arrival_seed,
                     "with --arrival poisson: the schedule's seed (default 1)")
        ->transform(whole_number(0));
    command_
        ->add_option("--scenario", args_.scenario,
                     "open-loop (default: at the arrival times, whatever the graph does), "
                     "single-stream (the next message when the last output arrived: latency "
                     "without queueing) or offline (every message at once: throughput), as "
                     "MLPerf LoadGen names them")
        ->check(CLI::IsMember({"open-loop", "single-stream", "offline"}))
        ->excludes(find_peak_);
    command_
        ->add_option("--monitor-wait", args_.monitor_wait,
                     "how the Monitor waits for outputs: sleep (default; each latency includes a "
                     "thread wake-up) or spin (no wake-up; keeps one core busy during the run)")
        ->check(CLI::IsMember({"sleep", "spin"}));
    auto* count = command_->add_option("--count", args_.count, "messages to send, warm-up included")
                      ->transform(whole_number(1));
    find_peak_->excludes(count);
    command_
        ->add_option("--duration", args_.duration,
                     "seconds to send for (count = rate x duration): 20, 20s, 500ms, 2min")
        ->transform(seconds_with_unit())
        ->excludes(count);
    command_
        ->add_option("--warmup", args_.warmup,
                     "first messages not counted (default: the benchmark's)")
        ->transform(whole_number(0));
    command_->add_option("--drain", args_.drain, "seconds to wait for outputs after the last send")
        ->transform(seconds_with_unit());
  }

  // Transport, backend, processes, domain, hosts and security of the graph.
  void declare_graph() {
    command_
        ->add_option("--rmw", args_.rmw,
                     "transport: intra, fastdds or cyclonedds (default: intra; fastdds for a "
                     "per-node layout)")
        ->check(CLI::IsMember({"intra", "fastdds", "cyclonedds"}));
    command_->add_option("--backend", args_.backend,
                         "run every node whose kernel has this backend on it (cpu, opencl, cuda "
                         "in a build with the CUDA toolkit, or a plug-in's); the others stay on "
                         "theirs (see robotperf list kernels)");
    command_->add_flag("--device-resident", args_.device_resident,
                       "keep images on the device between nodes that can hand them over there "
                       "(type adaptation, as NITROS; e.g. a1 with --backend cuda): a "
                       "configuration of its own, not the host-memory baseline");
    command_
        ->add_option("--processes", args_.processes,
                     "single (all nodes in one process) or per-node (default: the benchmark's)")
        ->check(CLI::IsMember({"single", "per-node"}));
    command_
        ->add_option("--domain", args_.domain,
                     "DDS domain id, or 'auto': one no other participant uses (default: "
                     "ROS_DOMAIN_ID or 0)")
        ->transform(domain_id_check(true));
    command_
        ->add_option("--host", args_.hosts,
                     "NAME=COMMAND: how to start a process on a host graph.yaml names (default: "
                     "ssh NAME --); repeatable")
        ->type_name("NAME=COMMAND");
    command_->add_flag("--netns", args_.netns,
                       "run the graph's other host in a network namespace of its own, joined to "
                       "the runner's by a veth pair (needs root)");
    command_->add_option("--link-rate", args_.link_rate,
                         "--netns: the link's rate limit, as tc writes it (default: 1gbit; none: "
                         "unshaped)");
    command_->add_option("--netem", args_.netem,
                         "--netns: netem's delay, jitter and loss on the link, e.g. "
                         "\"delay 1ms 0.1ms loss 0.1%\"");
    command_
        ->add_option("--connect-timeout", args_.connect_timeout_s,
                     "seconds the graph may take to start and connect before the run is refused "
                     "(default 15)")
        ->transform(seconds_with_unit())
        ->check(number_between(0.1, 3600.0));
    command_
        ->add_option("--security", args_.security,
                     "DDS Security: every participant presents the /robotperf enclave of this "
                     "keystore (robotperf security init DIR makes one)")
        ->type_name("DIR");
    command_
        ->add_option("--ros-distro", args_.ros_distro,
                     "ROS 2 release the DDS participants announce themselves as to the graph's "
                     "nodes: humble (24-byte GIDs, no type hashes), iron or jazzy (default)")
        ->check(CLI::IsMember({"humble", "iron", "jazzy"}));
  }

  // Where the results go, and what else is measured with them.
  void declare_output() {
    command_->add_option("--output", args_.output,
                         "folder for the results files (default: ./results)");
    command_->add_flag("--csv", args_.csv, "also write the per-message latencies as CSV");
    command_
        ->add_option("--label", args_.labels,
                     "KEY=VALUE recorded with the results, a series key in reports and a filter "
                     "of compare (label.KEY=VALUE); repeatable")
        ->check(label_check());
    command_
        ->add_option("--system", args_.system,
                     "what reports call this machine (default: its CPU and GPU models)")
        ->check(display_name_check());
    command_->add_flag("--quiet", args_.quiet, "no progress line");
    command_->add_flag("--report", args_.report,
                       "also write the HTML report of the run next to its results");
    command_->add_flag(
        "--strict", args_.strict,
        "refuse to run when a run rule is broken (see the warnings of a normal run)");
    add_power_options(command_, args_.power, true);
    add_scheduling_options(command_, args_.scheduling);
    command_
        ->add_option("--mode", args_.mode,
                     "black (Playback/Monitor) or grey (also record an LTTng trace and take the "
                     "results from it)")
        ->check(CLI::IsMember({"black", "grey"}));
    command_
        ->add_option("--trace-subbuf-size", args_.trace_subbuf,
                     "grey: per-CPU LTTng sub-buffer bytes (default: sized for the workload)")
        ->transform(whole_number(0));
  }

  RunArgs args_;
  CLI::App* command_ = nullptr;
  CLI::Option* find_peak_ = nullptr;
};

}  // namespace

std::unique_ptr<Command> run_command() {
  return std::make_unique<RunCommand>();
}

}  // namespace robotperf::cli
