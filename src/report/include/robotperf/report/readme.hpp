// A benchmark package's README.md, generated from its benchmark.yaml (and graph.yaml), as
// RobotPerf generates its benchmarks' READMEs. Same input, same bytes: nothing in it depends on
// the time, the machine or the order of a directory listing.
#pragma once

#include <filesystem>
#include <string>

namespace robotperf::report {

// Renders the README of the package in `package_dir`. Throws ReportError (benchmark.yaml) or
// harness::BenchmarkError (graph.yaml) naming the file when the package is broken.
std::string render_package_readme(const std::filesystem::path& package_dir);

// Text for one Markdown table cell: '|' escaped, line breaks folded into spaces.
std::string markdown_cell(const std::string& text);

}  // namespace robotperf::report
