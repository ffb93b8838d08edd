#include "bench_start.hpp"

#include "robotperf/categories/builtin.hpp"
#include "this_build.hpp"

namespace robotperf::bench {

void start_with_builtin_categories() {
  warn_about_this_build();
  categories::register_builtin_categories();
}

}  // namespace robotperf::bench
