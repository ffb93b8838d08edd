// Recording an LTTng session around a run, through the `lttng` command line
// (lttng-tools): start a session daemon when none runs, create a uniquely
// named session writing into a folder, enable the robotperf and ros2 events
// with the vpid, vtid and procname contexts, start, and on stop() stop and
// destroy it, leaving a complete CTF trace in the folder.
#pragma once

#include <cstddef>
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace robotperf::tracing {

// LTTng's tools are not installed: the message says how to install them.
class TracingUnavailable : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// An lttng command failed; the message holds its output.
class TracingError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct SessionOptions {
  std::filesystem::path output_dir;  // the trace folder; created by LTTng, must not exist
  std::string name_hint = "run";     // part of the session name (e.g. the benchmark id)
  std::size_t subbuf_bytes = 0;      // per-CPU sub-buffer size; 0 = subbuffer_bytes_for(0)
  std::size_t num_subbuf = 4;
  std::vector<std::string> events = {"robotperf:*", "ros2:*"};
  // When not empty, only these processes are recorded (LTTng's vpid tracker): a session otherwise
  // records every traced process of the user, and another robotperf run at the same time would
  // fill its buffers with events of no interest.
  std::vector<int> only_processes;
  // How long to wait for this process to register with a daemon we started.
  double register_timeout_s = 10.0;
};

namespace detail {
class DaemonUseLock;
}

class RecordingSession {
 public:
  // Throws TracingUnavailable when lttng-tools is missing, TracingError when a step fails.
  explicit RecordingSession(SessionOptions options);
  ~RecordingSession();  // destroys the session if stop() was not called
  RecordingSession(const RecordingSession&) = delete;
  RecordingSession& operator=(const RecordingSession&) = delete;

  // Stops tracing (waiting until every event is written) and destroys the session.
  void stop();

  const std::string& name() const { return name_; }
  const std::filesystem::path& output_dir() const { return options_.output_dir; }
  bool started_daemon() const { return started_daemon_; }
  std::size_t subbuf_bytes() const { return options_.subbuf_bytes; }

 private:
  // Waits for this process to register, then creates, configures and starts the session.
  void start();
  // `lttng destroy`; whether it succeeded (the session is then no longer active).
  bool destroy();

  SessionOptions options_;
  std::string name_;
  // Held from before the daemon is looked for until the session is gone: no other process stops
  // the daemon meanwhile (docs/design.md §4).
  std::unique_ptr<detail::DaemonUseLock> daemon_use_;
  bool started_daemon_ = false;
  bool active_ = false;
};

// Whether the lttng command-line tools are on PATH; otherwise `why` says how to install them.
bool lttng_available(std::string* why = nullptr);

// Starts `lttng-sessiond --daemonize` when no session daemon answers. Returns
// whether it started one.
bool ensure_session_daemon();

// A per-CPU sub-buffer size (power of two, 256 KiB .. 16 MiB) for a workload
// emitting `events_per_second`: four sub-buffers hold half a second of events.
std::size_t subbuffer_bytes_for(double events_per_second);

// Throws std::invalid_argument unless LTTng takes `bytes` as a sub-buffer size: a power of two
// from the page size to 1 GiB.
void check_subbuffer_bytes(std::size_t bytes);

}  // namespace robotperf::tracing
