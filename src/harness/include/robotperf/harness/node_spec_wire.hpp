// The nodes of a per-node run as the runner resolved them (RunOptions' overrides applied), as
// they travel to each node process: the child runs them as they are instead of applying the
// overrides to the package it loads.
#pragma once

#include <string>
#include <vector>

#include "robotperf/harness/benchmark_spec.hpp"

namespace robotperf::harness {

// JSON, written as hexadecimal digits: one word that a host's launcher passes as it is (ssh
// joins its arguments into one command line, which the remote shell splits again).
std::string encode_nodes(const std::vector<NodeSpec>& nodes);

// Replaces the nodes of `spec` (the package the child loaded) by those encoded. Throws
// std::invalid_argument when `encoded` is not what encode_nodes writes, or names other nodes.
void use_encoded_nodes(BenchmarkSpec& spec, const std::string& encoded);

}  // namespace robotperf::harness
