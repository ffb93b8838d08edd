// YAML scalars as robotperf's writers put them in the files they write (a bag's metadata.yaml,
// RobotPerf's benchmark.yaml): one quoting for every writer, so that a name that reads back in one
// file reads back in all of them.
#pragma once

#include <string>
#include <string_view>

namespace robotperf::files {

// `text` double-quoted, with the escapes every YAML 1.1/1.2 reader takes: \" \\ \n \t, and \xNN
// for the other control characters. UTF-8 text passes as it is.
std::string yaml_double_quoted(std::string_view text);

// A YAML scalar for `text`: plain when a reader cannot take it for anything else (a number, a
// boolean, null, a flow collection, a comment), else yaml_double_quoted.
std::string yaml_scalar(std::string_view text);

}  // namespace robotperf::files
