#include "this_build.hpp"

#include <cstdio>

#include "robotperf/build_info.hpp"
#include "robotperf/sysinfo/run_rules.hpp"

namespace robotperf::bench {

bool warn_about_this_build() {
  const auto warnings = sysinfo::build_warnings(build_info::kBuildType, build_info::kSanitized);
  for (const auto& w : warnings)
    std::printf("warning: %s (the figures below are not its speed)\n", w.message.c_str());
  std::fflush(stdout);
  return !warnings.empty();
}

}  // namespace robotperf::bench
