// The `run` verb's pieces: its arguments, the run options made of them, and the drivers of one
// run, a series (--repeat), a sweep (--sweep) and a peak search (--find-peak).
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "../command.hpp"
#include "../options.hpp"
#include "robotperf/harness/benchmark_spec.hpp"
#include "robotperf/harness/network_link.hpp"
#include "robotperf/harness/run.hpp"

namespace robotperf::cli {

struct RunArgs {
  std::string id;
  std::optional<std::string> rate;     // Hz, or "bag"
  std::optional<double> update_rate;   // Hz: the controller managers' loop rate
  std::optional<std::string> backend;  // --backend: nodes whose kernel has it run on it
  bool device_resident = false;        // --device-resident
  std::optional<double> duration, drain;
  std::optional<std::string> dataset, window;
  std::vector<std::string> remaps;
  double rate_scale = 1.0;
  std::string arrival = "fixed";
  std::string scenario = "open-loop";
  std::optional<uint64_t> arrival_seed;
  std::string monitor_wait = "sleep";
  // --find-peak and its bounds.
  bool find_peak = false;
  std::optional<double> loss_bound, latency_bound;
  double latency_percentile = 99;
  std::optional<std::string> rate_range;
  double peak_resolution = 5;
  // --repeat N [--repeat-pause S]
  std::size_t repeat = 1;
  double repeat_pause = 0;
  std::optional<std::size_t> count, warmup;
  // Default: the benchmark's process layout; fastdds for per-node, else intra.
  std::optional<std::string> rmw, processes;
  // --workload KEY=VALUE (over benchmark.yaml's workload), --sweep KEY=V1,V2,...
  std::vector<std::string> workload;
  std::optional<std::string> sweep;
  std::string output = "results";
  std::vector<std::string> labels;  // --label KEY=VALUE
  std::string system;               // --system NAME
  bool csv = false;
  bool quiet = false;
  bool report = false;
  bool strict = false;
  std::optional<std::string> domain;  // a number, or "auto"
  PowerArgs power;
  SchedulingArgs scheduling;
  std::string mode = "black";
  std::size_t trace_subbuf = 0;
  double callback_timeout_s = 30.0;
  // Several hosts: --host NAME=COMMAND (a launcher), or --netns with its link's shaping.
  std::vector<std::string> hosts;
  bool netns = false;
  std::string link_rate = "1gbit";
  std::string netem;
  std::string security;  // a keystore: DDS Security for every participant of the run
  double connect_timeout_s = 15.0;
  std::string ros_distro = "jazzy";
};

// --workload KEY=VALUE over the benchmark's workload.
void apply_workload(harness::BenchmarkSpec& spec, const RunArgs& args);

// The harness's options for a run of `spec` as `args` ask, checked before anything is measured.
// With --netns, `link` receives the network link, which must outlive the run.
harness::RunOptions run_options(const harness::BenchmarkSpec& spec, const RunArgs& args,
                                const Context& context, std::optional<harness::NetworkLink>& link);

// Before a grey run: removes what grey runs that were killed (or forced out before their
// clean-up ended) left, saying so on one line (tracing::remove_leftovers).
void remove_grey_leftovers(const RunArgs& args);

// The drivers; each returns the exit status.
int run_once(const harness::BenchmarkSpec& spec, const RunArgs& args,
             const harness::RunOptions& options);
int run_series(const harness::BenchmarkSpec& spec, const RunArgs& args,
               const harness::RunOptions& options);
int run_sweep(harness::BenchmarkSpec spec, const RunArgs& args, const harness::RunOptions& options);
int run_peak_search(const harness::BenchmarkSpec& spec, const RunArgs& args,
                    harness::RunOptions options);

}  // namespace robotperf::cli
