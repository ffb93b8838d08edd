// The robotperf executable: the composition root, the one place that links the built-in categories.
// It registers them, as a plug-in would register itself, and runs the command line, which knows
// them only through the registry.
#include <exception>

#include "robotperf/categories/builtin.hpp"
#include "robotperf/cli/command_line.hpp"
#include "robotperf/cli/exit_codes.hpp"

int main(int argc, char** argv) {
  using namespace robotperf;
  try {
    categories::register_builtin_categories();
  } catch (...) {
    return cli::report_error(std::current_exception());
  }
  return cli::run_command_line(argc, argv);
}
