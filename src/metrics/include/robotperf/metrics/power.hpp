// Power and energy of the machine during a measured window (docs/design.md §3.8): read from real
// sensors only — RAPL (powercap), hwmon, NVML, Jetson INA3221 rails, or an external meter —
// and "unavailable, because ..." otherwise, never 0.
//
// A source is either an energy counter (RAPL, hwmon energy*_input, NVML total energy), whose
// increase over the window is the energy, or a power gauge (hwmon power*_input, Jetson rails,
// NVML power usage, an external meter), whose readings are integrated over time (trapezoids).
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <string>
#include <thread>
#include <vector>

namespace robotperf::metrics {

enum class PowerSourceKind { kEnergyCounter, kPowerGauge };

struct PowerSourceInfo {
  std::string name;         // unique, e.g. "rapl:package-0", "nvml:gpu0", "jetson:VDD_IN"
  std::string type;         // "rapl", "hwmon", "nvml", "jetson", "external"
  std::string location;     // the file, library or command it reads
  std::string description;  // e.g. the GPU model; may be empty
  PowerSourceKind kind = PowerSourceKind::kPowerGauge;
  // Energy counters that wrap: the counter goes back to 0 after this many joules; 0 = never.
  double wrap_j = 0;
  // Part of the total. False for sources that a counted source already includes (RAPL core and
  // uncore inside their package, Jetson sub-rails when the module input rail exists, every other
  // source when a whole-machine meter is counted, ...).
  bool in_total = true;
  // Measures the whole machine's input power (an ACPI power meter, an external meter): every
  // other source is part of what it reads.
  bool whole_machine = false;
};

// What a device's source reports beside its power (NVML: a GPU): how busy it was and how much of
// its memory is in use.
struct DeviceLoad {
  double utilisation_percent = 0;  // of the time the device ran work, over its own last window
  uint64_t memory_used_bytes = 0;
  uint64_t memory_total_bytes = 0;
};

// A device's load over the window, from the readings of every sampling round.
struct DeviceLoadSummary {
  std::size_t readings = 0;
  double utilisation_mean_percent = 0;
  double utilisation_max_percent = 0;
  uint64_t memory_used_max_bytes = 0;
  uint64_t memory_total_bytes = 0;
};

class PowerSource {
 public:
  explicit PowerSource(PowerSourceInfo info) : info_(std::move(info)) {}
  virtual ~PowerSource() = default;
  PowerSource(const PowerSource&) = delete;
  PowerSource& operator=(const PowerSource&) = delete;

  const PowerSourceInfo& info() const { return info_; }
  // Discovery leaves a source out of the total once it has found a meter that includes it.
  void leave_out_of_total() { info_.in_total = false; }
  // Joules (energy counter) or watts (power gauge); nullopt with `error` set when it failed.
  virtual std::optional<double> read(std::string& error) = 0;
  // The device's load now, for sources that are a device's; nullopt otherwise or when it failed.
  virtual std::optional<DeviceLoad> load() { return std::nullopt; }

 private:
  PowerSourceInfo info_;
};

struct PowerOptions {
  std::filesystem::path sysfs_root = "/";  // tests point this at fixture trees
  // NVML is loaded at run time; there is no build dependency on the NVIDIA driver.
  std::string nvml_library = "libnvidia-ml.so.1";
  // Run once per sample through /bin/sh -c; must print watts as its first token.
  std::string meter_command;
  double meter_timeout_s = 2.0;
  // Source types to use ("rapl", "hwmon", "nvml", "jetson", "external"); empty = all found.
  std::set<std::string> types;
  std::chrono::nanoseconds period = std::chrono::milliseconds(100);
};

struct PowerDiscovery {
  std::vector<std::unique_ptr<PowerSource>> sources;
  // For each type that gave no source: why not, e.g. "nvml: libnvidia-ml.so.1 not loadable ...".
  std::vector<std::string> notes;
};

// Finds every power source of the machine (or of the fixture tree). Never throws for missing
// sensors; throws std::invalid_argument for a meter command that does not work or an unknown type.
PowerDiscovery discover_power_sources(const PowerOptions& options);

// The result of one source over the window.
struct SourceEnergy {
  PowerSourceInfo info;
  bool available = false;
  std::string unavailable_reason;
  double energy_j = 0;
  double average_w = 0;
  double span_s = 0;  // from its first to its last good reading
  std::size_t readings = 0;
  std::size_t failed_readings = 0;
  std::size_t wraps = 0;  // counter wrap-arounds seen
  std::string first_error;
  std::optional<DeviceLoadSummary> load;  // a device's source that reported its load
};

struct PowerReport {
  bool available = false;
  std::string unavailable_reason;  // when !available: why (never a number)
  std::vector<SourceEnergy> sources;
  // Over the available in_total sources: each source's average power × the window, so that a
  // source with failed readings at the start or end still stands for the whole window.
  double total_energy_j = 0;
  double total_average_w = 0;
  // The counted sources whose good readings covered less than the window, each with how much:
  // their share of the total energy is an estimate from their average.
  std::vector<std::string> estimated;
  double window_s = 0;  // the sampler's window: first to last sampling round
  double period_s = 0;
  std::size_t rounds = 0;    // sampling rounds taken
  std::size_t overruns = 0;  // rounds that started late because the previous one overran
  double sampler_cpu_s = 0;  // CPU time of the sampling thread itself
};

// The most a single machine under test can draw: a rack of the densest accelerators stays below
// it. A reading (or an energy step) beyond it is a broken sensor or meter, never a measurement.
inline constexpr double kMaxPhysicalWatts = 100'000;

// Integrates the readings of one source, in time order. Readings that are not finite, negative
// (gauges), or imply more than kMaxPhysicalWatts are counted as failed readings.
class EnergyIntegrator {
 public:
  explicit EnergyIntegrator(PowerSourceInfo info) : info_(std::move(info)) {}
  void add(int64_t time_ns, std::optional<double> value, const std::string& error = {});
  SourceEnergy result() const;

 private:
  PowerSourceInfo info_;
  std::optional<double> last_value_;
  int64_t first_ns_ = 0;
  int64_t last_ns_ = 0;
  double energy_j_ = 0;
  std::size_t readings_ = 0;
  std::size_t failed_ = 0;
  std::size_t wraps_ = 0;
  std::size_t resets_ = 0;
  std::string first_error_;
};

// All sources, read together in rounds. Not thread-safe: PowerSampler gives it one thread.
class PowerMeter {
 public:
  PowerMeter(std::vector<std::unique_ptr<PowerSource>> sources, std::vector<std::string> notes);
  // Reads every source once, at `time_ns` (CLOCK_MONOTONIC), and integrates.
  void sample_round(int64_t time_ns);
  PowerReport report() const;
  bool has_sources() const { return !sources_.empty(); }
  const std::vector<std::unique_ptr<PowerSource>>& sources() const { return sources_; }
  const std::vector<std::string>& notes() const { return notes_; }

 private:
  std::vector<std::unique_ptr<PowerSource>> sources_;
  std::vector<EnergyIntegrator> integrators_;
  std::vector<DeviceLoadSummary> loads_;  // per source; readings 0 when it reports none
  std::vector<std::string> notes_;
  std::size_t rounds_ = 0;
  int64_t first_ns_ = 0;
  int64_t last_ns_ = 0;
};

// Samples a PowerMeter on its own thread between begin() and end(), at absolute deadlines
// begin + k·period. begin() only wakes the thread, so it is cheap enough for the Playback thread.
class PowerSampler {
 public:
  PowerSampler(PowerMeter& meter, std::chrono::nanoseconds period);
  ~PowerSampler();
  PowerSampler(const PowerSampler&) = delete;
  PowerSampler& operator=(const PowerSampler&) = delete;

  // Called on the sampling thread right after the first and the last round, with their time
  // (CLOCK_MONOTONIC ns), so that other window measurements share the power window exactly.
  // Set before begin().
  void on_window_edges(std::function<void(int64_t)> at_first, std::function<void(int64_t)> at_last);

  void begin();
  // Takes the last round, stops the thread and returns the report. Without begin(), the report
  // says the window was never started.
  PowerReport end();

 private:
  void run();

  PowerMeter& meter_;
  std::chrono::nanoseconds period_;
  std::mutex mutex_;
  std::condition_variable cv_;
  bool begun_ = false;
  bool ending_ = false;
  std::size_t overruns_ = 0;
  double cpu_s_ = 0;
  std::function<void(int64_t)> at_first_, at_last_;
  std::thread thread_;
};

// {"available", "unavailable_reason"|..., "sources": [...], "total": {...}, ...}; per-message
// figures when `messages` > 0 and throughput per watt when `throughput_hz` > 0.
nlohmann::json to_json(const PowerReport& report, std::size_t messages, double throughput_hz);

// The sources found, for `robotperf sysinfo`: [{"name", "type", "location", ...}], plus notes.
nlohmann::json sources_to_json(const PowerDiscovery& discovery);

}  // namespace robotperf::metrics
