// The robotperf command line, as a library: the executable's composition root (src/app)
// registers the built-in categories, then hands it the arguments.
#pragma once

namespace robotperf::cli {

// Parses the command line, runs its verb and returns the process's exit status; errors are said
// in one line on stderr (exit_codes.hpp).
int run_command_line(int argc, char** argv);

}  // namespace robotperf::cli
