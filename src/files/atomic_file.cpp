#include "robotperf/files/atomic_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <map>
#include <optional>
#include <random>
#include <stdexcept>
#include <string>
#include <system_error>
#include <vector>

namespace robotperf::files {
namespace {

namespace fs = std::filesystem;

[[noreturn]] void fail(const fs::path& path, const std::string& step, int error_number) {
  throw std::runtime_error("cannot write " + path.string() + ": " + step + ": " +
                           std::system_category().message(error_number));
}

// Owns the temporary file until it has been renamed into place: closes the descriptor and removes
// the file on every early exit, so that a failure leaves nothing behind.
class TemporaryFile {
 public:
  TemporaryFile(fs::path path, int descriptor) : path_(std::move(path)), descriptor_(descriptor) {}
  TemporaryFile(const TemporaryFile&) = delete;
  TemporaryFile& operator=(const TemporaryFile&) = delete;
  ~TemporaryFile() {
    if (descriptor_ >= 0) ::close(descriptor_);
    if (!path_.empty()) ::unlink(path_.c_str());
  }

  const fs::path& path() const { return path_; }
  int descriptor() const { return descriptor_; }

  // Returns close()'s errno, or 0. The descriptor is gone either way (close is never retried).
  int close() {
    const int result = ::close(descriptor_);
    descriptor_ = -1;
    return result == 0 ? 0 : errno;
  }

  // Called once the file has been renamed: it is no longer ours to remove.
  void keep() { path_.clear(); }

 private:
  fs::path path_;
  int descriptor_;
};

// ".<name>.tmp-<pid>-<counter>-<random>": hidden, recognisable, and unique across threads,
// processes and PID namespaces sharing the directory.
fs::path temporary_path_for(const fs::path& path) {
  static std::atomic<unsigned long> counter{0};
  std::random_device random;
  char suffix[64];
  std::snprintf(suffix, sizeof(suffix), ".tmp-%ld-%lu-%08x", static_cast<long>(::getpid()),
                counter.fetch_add(1), static_cast<unsigned>(random()));
  return path.parent_path() / ("." + path.filename().string() + suffix);
}

TemporaryFile create_temporary_file(const fs::path& path) {
  constexpr int kAttempts = 16;
  for (int attempt = 0; attempt < kAttempts; ++attempt) {
    fs::path candidate = temporary_path_for(path);
    const int descriptor = ::open(candidate.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC,
                                  S_IRUSR | S_IWUSR | S_IRGRP | S_IWGRP | S_IROTH | S_IWOTH);
    if (descriptor >= 0) return TemporaryFile(std::move(candidate), descriptor);
    if (errno != EEXIST) fail(path, "creating temporary file " + candidate.string(), errno);
  }
  fail(path, "creating temporary file", EEXIST);
}

// Writes all of `content` to `descriptor`, which is `written_to` (a step of writing `path`).
void write_all(int descriptor, const fs::path& path, const std::string& written_to,
               std::string_view content) {
  while (!content.empty()) {
    const ssize_t written = ::write(descriptor, content.data(), content.size());
    if (written < 0) {
      if (errno == EINTR) continue;
      fail(path, "writing " + written_to, errno);
    }
    content.remove_prefix(static_cast<std::size_t>(written));
  }
}

void sync_directory(const fs::path& directory, const fs::path& path) {
  const int descriptor = ::open(directory.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (descriptor < 0) fail(path, "opening directory " + directory.string(), errno);
  const int result = ::fsync(descriptor);
  const int sync_error = errno;
  ::close(descriptor);
  // EINVAL: the file system cannot sync directories, so there is nothing more to do.
  if (result != 0 && sync_error != EINVAL) {
    fail(path, "syncing directory " + directory.string() + " after the rename", sync_error);
  }
}

// The directory `path` goes into, created when missing.
fs::path directory_for(const fs::path& path) {
  if (!path.has_filename()) fail(path, "the path names no file", EINVAL);
  const fs::path directory = path.has_parent_path() ? path.parent_path() : fs::path(".");
  std::error_code error;
  fs::create_directories(directory, error);
  if (error) fail(path, "creating directory " + directory.string(), error.value());
  return directory;
}

// Fills `file`, the temporary file beside `path`, with all of `content`, syncs and closes it:
// ready to be put in place. `mode`, when given, is set on it.
void fill_temporary(TemporaryFile& file, const fs::path& path, std::string_view content,
                    std::optional<mode_t> mode) {
  if (mode && ::fchmod(file.descriptor(), *mode) != 0) {
    fail(path, "setting the mode of " + file.path().string(), errno);
  }
  write_all(file.descriptor(), path, file.path().string(), content);
  if (::fsync(file.descriptor()) != 0) fail(path, "syncing " + file.path().string(), errno);
  if (const int close_error = file.close(); close_error != 0) {
    fail(path, "closing " + file.path().string(), close_error);
  }
}

// Puts `file` at `path` unless something is there already (then false, `file` untouched): a
// rename that refuses to replace, or, where the file system has none, a hard link (the
// temporary name is then removed with `file`).
bool place_without_replacing(TemporaryFile& file, const fs::path& path) {
  if (::renameat2(AT_FDCWD, file.path().c_str(), AT_FDCWD, path.c_str(), RENAME_NOREPLACE) == 0) {
    file.keep();
    return true;
  }
  if (errno == EEXIST) return false;
  if (errno != EINVAL && errno != ENOSYS) fail(path, "renaming " + file.path().string(), errno);
  if (::link(file.path().c_str(), path.c_str()) == 0) return true;
  if (errno == EEXIST) return false;
  fail(path, "linking " + file.path().string() + " to it", errno);
}

}  // namespace

void write_file_atomically(const fs::path& path, std::string_view content) {
  const fs::path directory = directory_for(path);
  std::optional<mode_t> existing_mode;
  struct stat existing {};
  if (::lstat(path.c_str(), &existing) == 0 && S_ISREG(existing.st_mode)) {
    existing_mode = existing.st_mode & 07777;
  }
  TemporaryFile file = create_temporary_file(path);
  fill_temporary(file, path, content, existing_mode);
  if (::rename(file.path().c_str(), path.c_str()) != 0) {
    fail(path, "renaming " + file.path().string() + " over it", errno);
  }
  file.keep();
  sync_directory(directory, path);
}

bool write_new_file_atomically(const fs::path& path, std::string_view content) {
  const fs::path directory = directory_for(path);
  TemporaryFile file = create_temporary_file(path);
  fill_temporary(file, path, content, std::nullopt);
  if (!place_without_replacing(file, path)) return false;
  sync_directory(directory, path);
  return true;
}

fs::path write_new_files(const fs::path& base, const std::map<std::string, std::string>& files) {
  constexpr int kNames = 1000;
  for (int n = 1; n <= kNames; ++n) {
    const fs::path candidate = n == 1 ? base : fs::path(base.string() + "-" + std::to_string(n));
    std::vector<fs::path> placed;
    bool taken = false;
    try {
      for (const auto& [suffix, content] : files) {
        const fs::path path = candidate.string() + suffix;
        if (!write_new_file_atomically(path, content)) {
          taken = true;
          break;
        }
        placed.push_back(path);
      }
    } catch (...) {
      // A set is written whole or not at all.
      for (const auto& path : placed) ::unlink(path.c_str());
      throw;
    }
    if (!taken) return candidate;
    // Another writer's file (or a stray one) holds a name of the set: the set moves on whole.
    for (const auto& path : placed) ::unlink(path.c_str());
  }
  fail(base, "every name up to -" + std::to_string(kNames) + " is taken", EEXIST);
}

bool is_standard_output(const fs::path& path) {
  return path == "-";
}

void write_output(const fs::path& path, std::string_view content) {
  if (is_standard_output(path)) {
    std::fwrite(content.data(), 1, content.size(), stdout);
    if (std::fflush(stdout) != 0) fail("standard output", "writing to it", errno);
    return;
  }
  struct stat target {};
  if (::stat(path.c_str(), &target) == 0 && !S_ISREG(target.st_mode) && !S_ISDIR(target.st_mode)) {
    const int descriptor = ::open(path.c_str(), O_WRONLY | O_CLOEXEC);
    if (descriptor < 0) fail(path, "opening it", errno);
    try {
      write_all(descriptor, path, "to it", content);
    } catch (...) {
      ::close(descriptor);
      throw;
    }
    if (::close(descriptor) != 0) fail(path, "closing it", errno);
    return;
  }
  write_file_atomically(path, content);
}

}  // namespace robotperf::files
