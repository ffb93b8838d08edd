// Where a file that a name from a benchmark package becomes part of may go.
#pragma once

#include <filesystem>
#include <string>

namespace robotperf::files {

// Whether `path` names something inside `folder` (at any depth), judged on the paths' text as
// given, before either exists: no "..", no other absolute root, not `folder` itself.
bool is_inside(const std::filesystem::path& folder, const std::filesystem::path& path);

// `folder` / `name`, checked to stay inside `folder` (is_inside); throws std::invalid_argument
// naming both otherwise. Every file a run writes under --output is named through it.
std::filesystem::path path_inside(const std::filesystem::path& folder, const std::string& name);

}  // namespace robotperf::files
