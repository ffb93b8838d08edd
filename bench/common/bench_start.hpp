// What every bench that loads robotperf's benchmarks or datasets does first, as the robotperf
// executable does at start-up: the build warning, then the built-in categories registered.
#pragma once

namespace robotperf::bench {

// Prints a "warning:" line for each reason this build's times are not robotperf's
// (warn_about_this_build), then registers the built-in categories.
void start_with_builtin_categories();

}  // namespace robotperf::bench
