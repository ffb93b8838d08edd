// The one line a command line CLI11 refused is said in: what is wrong, with "did you mean" when
// a verb or an option is a typo of one that exists, and which --help to read.
#pragma once

#include <CLI/CLI.hpp>
#include <string>
#include <vector>

namespace robotperf::cli {

// `args` are the arguments after the program's name; `error` what CLI11 threw for them.
std::string parse_error_line(CLI::App& app, const std::vector<std::string>& args,
                             const CLI::ParseError& error);

// The members of the first "{a,b,c}" in `text`: an IsMember check's, as CLI11 writes them in a
// type name ("TEXT:{black,grey}") and in the error it throws ("x not in {black,grey}").
std::vector<std::string> members_in_braces(const std::string& text);

// "robotperf results list": the command `app` stands for.
std::string command_path(const CLI::App* app);

// `app`'s subcommand `name`; throws std::invalid_argument saying it has none, with the nearest.
CLI::App& subcommand_of(CLI::App& app, const std::string& name);

}  // namespace robotperf::cli
