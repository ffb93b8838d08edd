// What a grey run makes outside its process — an LTTng session, the session daemon when none
// ran, a temporary trace folder — is undone by the run itself; a run forced out by a second
// signal undoes it through clean_up_at_forced_exit(), and what a killed run left is removed by
// the next grey run (remove_leftovers). Nothing robotperf did not make is touched: each is
// marked with the process that made it (a session's name, a marker file in the folder, a file
// beside the daemon's pid file), and only what a process that no longer runs made is removed.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace robotperf::tracing {

// A folder of this run's own under `parent` (.trace-XXXXXX, made with mkdtemp, marked as
// robotperf's), for a trace that is moved elsewhere once the run is named; removed with what is
// left in it when this object goes, and by clean_up_at_forced_exit() until then. One at a time.
class TemporaryTraceFolder {
 public:
  // Throws std::runtime_error, saying why, when the folder cannot be made.
  explicit TemporaryTraceFolder(const std::filesystem::path& parent);
  ~TemporaryTraceFolder();
  TemporaryTraceFolder(const TemporaryTraceFolder&) = delete;
  TemporaryTraceFolder& operator=(const TemporaryTraceFolder&) = delete;

  // Where the trace goes: inside the folder, not yet there (LTTng makes it).
  std::filesystem::path trace_path() const { return folder_ / "trace"; }

 private:
  std::filesystem::path folder_;
};

// For a signal handler ending the process at once: destroys the recording session this process
// made, stops the session daemon it started (unless another session uses it) and removes its
// temporary trace folder, waiting a few seconds at most. Async-signal-safe.
void clean_up_at_forced_exit() noexcept;

// Removes what grey runs whose process no longer runs left: their temporary trace folders in
// `output_folder`, their recording sessions and a session daemon one started (when no session
// uses it). Returns what was removed, each named; never throws.
std::vector<std::string> remove_leftovers(const std::filesystem::path& output_folder);

}  // namespace robotperf::tracing
