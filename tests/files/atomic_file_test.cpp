#include "robotperf/files/atomic_file.hpp"

#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

#include <csignal>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <set>
#include <stdexcept>
#include <string>
#include <thread>

namespace robotperf::files {
namespace {

namespace fs = std::filesystem;

class AtomicFileTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* test = ::testing::UnitTest::GetInstance()->current_test_info();
    directory_ = fs::temp_directory_path() / ("robotperf_atomic_" + std::string(test->name()) +
                                              "_" + std::to_string(::getpid()));
    fs::remove_all(directory_);
    fs::create_directories(directory_);
  }
  void TearDown() override { fs::remove_all(directory_); }

  static std::string read(const fs::path& path) {
    std::ifstream stream(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(stream), std::istreambuf_iterator<char>()};
  }

  // Names of all entries directly in `directory`, temporary files included.
  static std::set<std::string> entries(const fs::path& directory) {
    std::set<std::string> names;
    for (const auto& entry : fs::directory_iterator(directory)) {
      names.insert(entry.path().filename().string());
    }
    return names;
  }

  static std::string error_message(const fs::path& path, std::string_view content) {
    try {
      write_file_atomically(path, content);
    } catch (const std::runtime_error& error) {
      return error.what();
    }
    ADD_FAILURE() << "write_file_atomically(" << path << ") did not throw";
    return {};
  }

  fs::path directory_;
};

TEST_F(AtomicFileTest, WritesContent) {
  const fs::path path = directory_ / "results.json";
  const std::string content =
      std::string("{\"a\": 1}\n") + std::string(1 << 20, 'x') + '\0' + "end";
  write_file_atomically(path, content);
  EXPECT_EQ(read(path), content);
  EXPECT_EQ(entries(directory_), std::set<std::string>{"results.json"});
}

TEST_F(AtomicFileTest, WritesEmptyContent) {
  const fs::path path = directory_ / "empty.txt";
  write_file_atomically(path, "");
  EXPECT_TRUE(fs::is_regular_file(path));
  EXPECT_EQ(fs::file_size(path), 0u);
}

TEST_F(AtomicFileTest, OverwritesExistingFileAndKeepsItsMode) {
  const fs::path path = directory_ / "results.json";
  write_file_atomically(path, "first version, rather long\n");
  fs::permissions(path, fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read);
  write_file_atomically(path, "second\n");
  EXPECT_EQ(read(path), "second\n");
  EXPECT_EQ(fs::status(path).permissions(),
            fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read);
  EXPECT_EQ(entries(directory_), std::set<std::string>{"results.json"});
}

// Results are never overwritten: a new file refuses a taken name, and a run's set of files whose
// name is taken (two runs started in the same millisecond) goes under the next free one, whole.
TEST_F(AtomicFileTest, ResultsWrittenUnderOneNameTwiceKeepBoth) {
  const fs::path json = directory_ / "a1-intra-20261127T073315239Z.json";
  EXPECT_TRUE(write_new_file_atomically(json, "first\n"));
  EXPECT_FALSE(write_new_file_atomically(json, "second\n"));
  EXPECT_EQ(read(json), "first\n");
  EXPECT_EQ(entries(directory_), std::set<std::string>{json.filename().string()});

  const fs::path base = directory_ / "a1-fastdds-20261127T073315239Z";
  const std::map<std::string, std::string> one = {{".json", "{\"run\": 1}"},
                                                  {".latencies.csv", "1"}};
  const std::map<std::string, std::string> two = {{".json", "{\"run\": 2}"},
                                                  {".latencies.csv", "2"}};
  EXPECT_EQ(write_new_files(base, one), base);
  const fs::path second = base.string() + "-2";
  EXPECT_EQ(write_new_files(base, two), second);
  EXPECT_EQ(read(base.string() + ".json"), "{\"run\": 1}");
  EXPECT_EQ(read(base.string() + ".latencies.csv"), "1");
  EXPECT_EQ(read(second.string() + ".json"), "{\"run\": 2}");
  EXPECT_EQ(read(second.string() + ".latencies.csv"), "2");
  // A stray file holding one name of a set moves the whole set on, leaving no part behind.
  write_file_atomically(base.string() + "-3.latencies.csv", "stray");
  const fs::path fourth = base.string() + "-4";
  EXPECT_EQ(write_new_files(base, one), fourth);
  EXPECT_FALSE(fs::exists(base.string() + "-3.json"));
  EXPECT_EQ(read(base.string() + "-3.latencies.csv"), "stray");
  EXPECT_EQ(entries(directory_).size(), 8u);  // no temporary file left
}

TEST_F(AtomicFileTest, NewFileModeFollowsUmask) {
  const mode_t previous = ::umask(022);
  write_file_atomically(directory_ / "new.txt", "x");
  ::umask(previous);
  EXPECT_EQ(fs::status(directory_ / "new.txt").permissions(),
            fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read |
                fs::perms::others_read);
}

TEST_F(AtomicFileTest, CreatesMissingParentDirectories) {
  const fs::path path = directory_ / "run" / "2024" / "a1" / "results.json";
  write_file_atomically(path, "nested");
  EXPECT_EQ(read(path), "nested");
  EXPECT_EQ(entries(path.parent_path()), std::set<std::string>{"results.json"});
}

TEST_F(AtomicFileTest, ParentThatIsAFileThrowsAndLeavesItAlone) {
  const fs::path blocker = directory_ / "blocker";
  write_file_atomically(blocker, "old content");
  const std::string message = error_message(blocker / "results.json", "new");
  EXPECT_NE(message.find((blocker / "results.json").string()), std::string::npos) << message;
  EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  EXPECT_EQ(read(blocker), "old content");
  EXPECT_EQ(entries(directory_), std::set<std::string>{"blocker"});
}

TEST_F(AtomicFileTest, DirectoryInTheWayThrowsAndLeavesNoTemporaryFile) {
  const fs::path target = directory_ / "results.json";
  fs::create_directories(target / "inside");
  const std::string message = error_message(target, "new");
  EXPECT_NE(message.find(target.string()), std::string::npos) << message;
  EXPECT_NE(message.find("renaming"), std::string::npos) << message;
  EXPECT_TRUE(fs::is_directory(target / "inside"));
  EXPECT_EQ(entries(directory_), std::set<std::string>{"results.json"});
}

TEST_F(AtomicFileTest, FailedWriteLeavesOldFileIntactAndNoTemporaryFile) {
  // RLIMIT_FSIZE makes write() fail with EFBIG part-way through, even for root.
  const fs::path path = directory_ / "results.json";
  write_file_atomically(path, "old content");

  rlimit previous{};
  ASSERT_EQ(::getrlimit(RLIMIT_FSIZE, &previous), 0);
  const auto previous_handler = std::signal(SIGXFSZ, SIG_IGN);
  rlimit limited = previous;
  limited.rlim_cur = 4096;
  ASSERT_EQ(::setrlimit(RLIMIT_FSIZE, &limited), 0);
  const std::string message = error_message(path, std::string(1 << 16, 'n'));
  ASSERT_EQ(::setrlimit(RLIMIT_FSIZE, &previous), 0);
  std::signal(SIGXFSZ, previous_handler);

  EXPECT_NE(message.find(path.string()), std::string::npos) << message;
  EXPECT_NE(message.find("File too large"), std::string::npos) << message;
  EXPECT_EQ(read(path), "old content");
  EXPECT_EQ(entries(directory_), std::set<std::string>{"results.json"});
}

TEST_F(AtomicFileTest, PathWithoutFileNameThrows) {
  const std::string message = error_message(directory_.string() + "/", "x");
  EXPECT_NE(message.find("names no file"), std::string::npos) << message;
}

// Output a user names may be a device or a pipe (`--md /dev/stdout`, `--md >(less)`): written
// through, never replaced by a regular file, nor its link by one.
TEST_F(AtomicFileTest, OutputToAPipeOrItsLinkIsWrittenThrough) {
  const fs::path fifo = directory_ / "pipe";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const fs::path link = directory_ / "stdout";
  fs::create_symlink(fifo, link);
  for (const fs::path& target : {fifo, link}) {
    std::string got;
    std::thread reader([&] {
      std::ifstream in(fifo, std::ios::binary);
      got.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    });
    write_output(target, "# report\n");
    reader.join();
    EXPECT_EQ(got, "# report\n") << target;
  }
  EXPECT_TRUE(fs::is_fifo(fs::symlink_status(fifo)));
  EXPECT_TRUE(fs::is_symlink(fs::symlink_status(link)));
  EXPECT_EQ(entries(directory_), (std::set<std::string>{"pipe", "stdout"}));
}

TEST_F(AtomicFileTest, DashIsStandardOutputAndFilesAreStillAtomic) {
  ::testing::internal::CaptureStdout();
  write_output("-", "to stdout\n");
  EXPECT_EQ(::testing::internal::GetCapturedStdout(), "to stdout\n");
  EXPECT_TRUE(is_standard_output("-"));
  EXPECT_FALSE(is_standard_output(directory_ / "-"));
  const fs::path file = directory_ / "report.md";
  write_output(file, "a file\n");
  EXPECT_EQ(read(file), "a file\n");
  EXPECT_TRUE(fs::is_regular_file(fs::symlink_status(file)));
}

}  // namespace
}  // namespace robotperf::files
