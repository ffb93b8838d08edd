// The git revision a folder is checked out at, read from the repository's files (no git process):
// the automatic label of a run of a user's own package (docs/design.md §3.7).
#pragma once

#include <filesystem>
#include <optional>
#include <string>

namespace robotperf::sysinfo {

// The 40-hex commit HEAD names in the git repository holding `folder` (the folder itself or one
// above it), following a branch through its loose ref or packed-refs; a `.git` file (a worktree,
// a submodule) is followed to its git folder. Nothing when `folder` is in no repository or HEAD
// cannot be resolved (an unborn branch).
std::optional<std::string> git_revision_of(const std::filesystem::path& folder);

}  // namespace robotperf::sysinfo
