// Whether this build can give the figures a bench is for: an unoptimised or sanitized one makes
// every time several times longer (the run rules warn a run of it; a bench says it too).
#pragma once

namespace robotperf::bench {

// Prints a "warning:" line for each reason this build's times are not robotperf's; returns
// whether there was one.
bool warn_about_this_build();

}  // namespace robotperf::bench
