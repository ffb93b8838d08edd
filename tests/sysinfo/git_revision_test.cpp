// git_revision_of against real repositories made by git itself: a branch in a loose ref, the same
// after `git pack-refs`, a detached HEAD, a worktree (a .git file), and a folder in no repository.
#include "robotperf/sysinfo/git_revision.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

namespace robotperf::sysinfo {
namespace {

namespace fs = std::filesystem;

// What a shell command prints (its last newline dropped); fails the test when it fails.
std::string output_of(const std::string& command) {
  std::string out;
  FILE* p = popen(command.c_str(), "r");
  if (p == nullptr) return out;
  std::array<char, 256> buffer{};
  while (fgets(buffer.data(), buffer.size(), p) != nullptr) out += buffer.data();
  EXPECT_EQ(pclose(p), 0) << command;
  if (!out.empty() && out.back() == '\n') out.pop_back();
  return out;
}

class GitRevision : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_EQ(std::system("command -v git >/dev/null"), 0) << "git is not installed";
    dir_ = fs::temp_directory_path() / ("robotperf-git-" + std::to_string(getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "repo" / "pkg" / "deep");
    git("init -q -b main && git -c user.name=t -c user.email=t@t commit -q --allow-empty -m one");
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string git(const std::string& args) {
    return output_of("cd " + (dir_ / "repo").string() + " && git " + args);
  }
  fs::path dir_;
};

TEST_F(GitRevision, FollowsTheBranchLooseOrPacked) {
  const std::string head = git("rev-parse HEAD");
  ASSERT_EQ(head.size(), 40u);
  EXPECT_EQ(git_revision_of(dir_ / "repo" / "pkg" / "deep"), head) << "from a folder inside";
  git("pack-refs --all");
  ASSERT_FALSE(fs::exists(dir_ / "repo" / ".git" / "refs" / "heads" / "main"));
  EXPECT_EQ(git_revision_of(dir_ / "repo"), head) << "from packed-refs";
}

TEST_F(GitRevision, ReadsADetachedHeadAndAWorktree) {
  const std::string first = git("rev-parse HEAD");
  git("-c user.name=t -c user.email=t@t commit -q --allow-empty -m two");
  git("worktree add -q --detach ../tree " + first);
  EXPECT_EQ(git_revision_of(dir_ / "tree"), first) << "a worktree's .git file, detached";
  git("checkout -q " + first);
  EXPECT_EQ(git_revision_of(dir_ / "repo"), first);
}

TEST_F(GitRevision, NothingOutsideARepositoryOrOnAnUnbornBranch) {
  fs::create_directories(dir_ / "plain");
  EXPECT_EQ(git_revision_of(dir_ / "plain"), std::nullopt);
  fs::create_directories(dir_ / "unborn");
  output_of("cd " + (dir_ / "unborn").string() + " && git init -q -b main");
  EXPECT_EQ(git_revision_of(dir_ / "unborn"), std::nullopt);
}

}  // namespace
}  // namespace robotperf::sysinfo
