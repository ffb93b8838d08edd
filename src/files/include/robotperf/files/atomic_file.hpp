// Crash-safe file replacement for what robotperf writes (results, reports, bags' metadata): a
// reader sees either the old file or the complete new one, never a truncated mix, even if the
// process or the machine dies mid-write.
#pragma once

#include <filesystem>
#include <map>
#include <string>
#include <string_view>

namespace robotperf::files {

// Writes `content` to `path` atomically: creates missing parent directories, writes a uniquely
// named temporary file in the same directory, fsyncs it, renames it over `path` and fsyncs the
// directory so that the rename itself is durable.
//
// A new file gets mode 0666 minus the umask; a replaced file keeps its mode. If `path` is a
// symbolic link, the link itself is replaced. On failure throws std::runtime_error with one line
// naming the path, the failed step and the system's error text; up to the rename, an existing file
// at `path` is untouched and the temporary file is removed.
void write_file_atomically(const std::filesystem::path& path, std::string_view content);

// As write_file_atomically, but never replaces anything at `path`: returns false, writing
// nothing, when something is there already (even one that appears while it writes). For results,
// which are never overwritten.
bool write_new_file_atomically(const std::filesystem::path& path, std::string_view content);

// Writes a set of files that belong together, <base><suffix> for each of `files`, each with
// write_new_file_atomically: when any name of the set is taken (another run of the same benchmark
// and transport started in the same millisecond), the whole set goes under <base>-2, <base>-3,
// ... instead. Returns the base used. Throws std::runtime_error as write_file_atomically does.
std::filesystem::path write_new_files(const std::filesystem::path& base,
                                      const std::map<std::string, std::string>& files);

// Writes output a user named: "-" is standard output; a path that is, or links to, something
// other than a regular file or a directory (a terminal, a pipe, /dev/stdout) is written through
// as it is, since replacing it would replace the device or its link; anything else is written
// with write_file_atomically. Throws std::runtime_error as that does.
void write_output(const std::filesystem::path& path, std::string_view content);

// Whether write_output(path, ...) writes to standard output.
bool is_standard_output(const std::filesystem::path& path);

}  // namespace robotperf::files
