#pragma once

// Answers checked across backends (docs/design.md §6): a run whose nodes computed on another
// backend than the host CPU has a sample of its outputs compared with what the same nodes on
// `cpu` answer to the same inputs. An accelerator that computes a slightly different answer is
// caught here whether or not the benchmark has ground truth (a bag has none).

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "robotperf/harness/benchmark_spec.hpp"
#include "robotperf/harness/dataset.hpp"
#include "robotperf/plugin/output_comparison.hpp"
#include "robotperf/rmw/transport.hpp"

namespace robotperf::harness {

struct BackendCheck {
  std::string backend;       // the nodes' other backend(s), e.g. "opencl"
  std::string output_type;   // what was compared
  std::size_t compared = 0;  // outputs compared with the cpu answer to the same inputs
  double agreement = 0;      // the worst output's share of elements within the tolerance
  double required = 0;       // the least share that passes
  std::string criterion;     // "|difference| <= 1 on pixel channels"
  bool passed = false;
  std::vector<std::string> reasons;  // why not, one line each
};

// How two answers of one output type compare: the comparison registered for the type
// (plugin::Registrar::add_output_comparison, by the category or plug-in whose kernels answer with
// it), nullopt for a type without one.
using plugin::Agreement;
std::optional<Agreement> compare_answers(const std::string& ros_type, const void* accelerated,
                                         const void* cpu);
bool has_comparison(const std::string& ros_type);

// Refuses a backend this robotperf cannot run on any machine (run --backend): throws
// std::invalid_argument with "--backend <name>: " and its registered entry's one line
// (plugin::BackendHooks::unavailable_reason). Nothing for cpu, a backend it can run, or a name no
// category or plug-in registered (override_backend then names the backends the kernels have).
void check_backend_available(const std::string& backend);

// Whether `spec` runs a node on another backend than cpu.
bool uses_other_backend(const BenchmarkSpec& spec);

// Feeds the frames of `kept` (message ID, output) through the benchmark's own nodes built on
// `cpu`, on an intra transport of their own, one frame at a time in ID order, and compares each
// answer with the kept output. nullopt when every node ran on cpu, nothing was kept or the output
// type has no comparison. Throws when the check cannot be made: std::runtime_error for a node
// whose kernel has no cpu backend (no reference), or whatever building the nodes on cpu throws.
std::optional<BackendCheck> check_backend_answers(
    const BenchmarkSpec& spec, const Dataset& dataset,
    const std::vector<std::pair<uint64_t, rmw::MessagePtr>>& kept);

}  // namespace robotperf::harness
