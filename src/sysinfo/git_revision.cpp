#include "robotperf/sysinfo/git_revision.hpp"

#include <algorithm>
#include <fstream>
#include <vector>
#include <system_error>

namespace robotperf::sysinfo {
namespace {

namespace fs = std::filesystem;

std::optional<std::string> first_line(const fs::path& file) {
  std::ifstream in(file);
  std::string line;
  if (!std::getline(in, line)) return std::nullopt;
  while (!line.empty() && (line.back() == '\r' || line.back() == ' ')) line.pop_back();
  return line;
}

bool is_commit(const std::string& text) {
  return text.size() == 40 && std::ranges::all_of(text, [](char c) {
           return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f');
         });
}

// The git folder of the repository holding `folder`: `.git` there or above, or where a `.git`
// file ("gitdir: PATH") points.
std::optional<fs::path> git_folder(const fs::path& folder) {
  std::error_code ec;
  fs::path at = fs::absolute(folder, ec);
  if (ec) return std::nullopt;
  for (; !at.empty(); at = at.parent_path()) {
    // A check's error (a missing .git sets one) only means "not here".
    std::error_code missing;
    const fs::path dot_git = at / ".git";
    if (fs::is_directory(dot_git, missing)) return dot_git;
    if (fs::is_regular_file(dot_git, missing)) {
      const auto line = first_line(dot_git);
      if (!line || !line->starts_with("gitdir: ")) return std::nullopt;
      const fs::path target = line->substr(8);
      return target.is_absolute() ? target : at / target;
    }
    if (at == at.parent_path()) break;
  }
  return std::nullopt;
}

// A ref's commit: its loose file, or its line in packed-refs. A worktree's git folder keeps
// branches in the main repository's (its `commondir`).
std::optional<std::string> resolve(const fs::path& git, const std::string& ref) {
  std::vector<fs::path> places{git};
  if (const auto common = first_line(git / "commondir"))
    places.push_back(fs::path(*common).is_absolute() ? fs::path(*common) : git / *common);
  for (const auto& place : places) {
    if (const auto loose = first_line(place / ref); loose && is_commit(*loose)) return loose;
    std::ifstream packed(place / "packed-refs");
    for (std::string line; std::getline(packed, line);) {
      if (line.size() > 41 && line[40] == ' ' && line.substr(41) == ref &&
          is_commit(line.substr(0, 40)))
        return line.substr(0, 40);
    }
  }
  return std::nullopt;
}

}  // namespace

std::optional<std::string> git_revision_of(const fs::path& folder) {
  const auto git = git_folder(folder);
  if (!git) return std::nullopt;
  const auto head = first_line(*git / "HEAD");
  if (!head) return std::nullopt;
  if (is_commit(*head)) return head;  // a detached HEAD
  if (!head->starts_with("ref: ")) return std::nullopt;
  return resolve(*git, head->substr(5));
}

}  // namespace robotperf::sysinfo
