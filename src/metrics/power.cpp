// Integration of power readings over the measured window, and the sampling thread.
#include "robotperf/metrics/power.hpp"

#include <time.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace robotperf::metrics {
namespace {

int64_t steady_ns(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(t.time_since_epoch()).count();
}

double thread_cpu_s() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + static_cast<double>(ts.tv_nsec) * 1e-9;
}

const char* kind_name(PowerSourceKind kind) {
  return kind == PowerSourceKind::kEnergyCounter ? "energy_counter" : "power_gauge";
}

nlohmann::json number_or_null(bool available, double value) {
  return available ? nlohmann::json(value) : nlohmann::json(nullptr);
}

}  // namespace

void EnergyIntegrator::add(int64_t time_ns, std::optional<double> value, const std::string& error) {
  auto fail = [&](const std::string& why) {
    ++failed_;
    if (first_error_.empty()) first_error_ = why;
  };
  if (!value) return fail(error);
  const bool gauge = info_.kind == PowerSourceKind::kPowerGauge;
  if (!std::isfinite(*value) || (gauge && (*value < 0 || *value > kMaxPhysicalWatts))) {
    char buf[160];
    std::snprintf(buf, sizeof buf, "reading %g %s is not physical (expected 0 to %g W)", *value,
                  gauge ? "W" : "J", kMaxPhysicalWatts);
    return fail(buf);
  }
  if (!gauge && last_value_ && time_ns > last_ns_ && *value > *last_value_ &&
      (*value - *last_value_) / (static_cast<double>(time_ns - last_ns_) * 1e-9) >
          kMaxPhysicalWatts) {
    char buf[160];
    std::snprintf(buf, sizeof buf, "energy counter rose %g J in %g s: more than %g W",
                  *value - *last_value_, static_cast<double>(time_ns - last_ns_) * 1e-9,
                  kMaxPhysicalWatts);
    return fail(buf);
  }
  ++readings_;
  if (!last_value_) {
    first_ns_ = last_ns_ = time_ns;
    last_value_ = value;
    return;
  }
  if (info_.kind == PowerSourceKind::kEnergyCounter) {
    double delta = *value - *last_value_;
    if (delta < 0) {
      // A counter in [0, wrap) that went back passed its end once (the period is far shorter than
      // the time a wrap takes: minutes even for a 250 W package).
      if (info_.wrap_j > 0 && *last_value_ <= info_.wrap_j) {
        delta += info_.wrap_j;
        ++wraps_;
      } else {
        delta = 0;
        ++resets_;
      }
    }
    energy_j_ += delta;
  } else {
    energy_j_ += 0.5 * (*last_value_ + *value) * static_cast<double>(time_ns - last_ns_) * 1e-9;
  }
  last_value_ = value;
  last_ns_ = time_ns;
}

SourceEnergy EnergyIntegrator::result() const {
  SourceEnergy r;
  r.info = info_;
  r.readings = readings_;
  r.failed_readings = failed_;
  r.wraps = wraps_;
  r.first_error = first_error_;
  r.span_s = static_cast<double>(last_ns_ - first_ns_) * 1e-9;
  if (readings_ == 0) {
    r.unavailable_reason =
        "no reading succeeded" + (first_error_.empty() ? "" : ": " + first_error_);
  } else if (readings_ < 2 || r.span_s <= 0) {
    r.unavailable_reason =
        "only one good reading in the window (window shorter than the sampling period?)";
  } else if (resets_ > 0) {
    r.unavailable_reason = "the energy counter went backwards " + std::to_string(resets_) +
                           " time(s) with no known wrap range: energy unknown";
  } else {
    r.available = true;
    r.energy_j = energy_j_;
    r.average_w = energy_j_ / r.span_s;
  }
  return r;
}

PowerMeter::PowerMeter(std::vector<std::unique_ptr<PowerSource>> sources,
                       std::vector<std::string> notes)
    : sources_(std::move(sources)), notes_(std::move(notes)) {
  for (const auto& s : sources_) integrators_.emplace_back(s->info());
  loads_.resize(sources_.size());
}

void PowerMeter::sample_round(int64_t time_ns) {
  std::string error;
  for (std::size_t i = 0; i < sources_.size(); ++i) {
    error.clear();
    const auto value = sources_[i]->read(error);
    integrators_[i].add(time_ns, value, error);
    if (const auto load = sources_[i]->load()) {
      DeviceLoadSummary& l = loads_[i];
      // The mean is kept as a running mean of the rounds' readings.
      ++l.readings;
      l.utilisation_mean_percent += (load->utilisation_percent - l.utilisation_mean_percent) /
                                    static_cast<double>(l.readings);
      l.utilisation_max_percent = std::max(l.utilisation_max_percent, load->utilisation_percent);
      l.memory_used_max_bytes = std::max(l.memory_used_max_bytes, load->memory_used_bytes);
      l.memory_total_bytes = load->memory_total_bytes;
    }
  }
  if (rounds_ == 0) first_ns_ = time_ns;
  last_ns_ = time_ns;
  ++rounds_;
}

PowerReport PowerMeter::report() const {
  PowerReport r;
  r.rounds = rounds_;
  r.window_s = static_cast<double>(last_ns_ - first_ns_) * 1e-9;
  std::string failures;
  for (std::size_t i = 0; i < integrators_.size(); ++i) {
    SourceEnergy s = integrators_[i].result();
    if (loads_[i].readings > 0) s.load = loads_[i];
    if (s.available && s.info.in_total) {
      r.available = true;
      // Each source's energy over its own first-to-last good reading would add up spans of
      // different lengths: the total is over the window, as the messages per joule are.
      r.total_energy_j += s.average_w * r.window_s;
      r.total_average_w += s.average_w;
      if (s.span_s < r.window_s) {
        char buf[160];
        std::snprintf(buf, sizeof buf,
                      "%s read for %.3f s of the %.3f s window (its average taken for the rest)",
                      s.info.name.c_str(), s.span_s, r.window_s);
        r.estimated.push_back(buf);
      }
    }
    if (!s.available) {
      failures += (failures.empty() ? "" : "; ") + s.info.name + ": " + s.unavailable_reason;
    }
    r.sources.push_back(std::move(s));
  }
  if (sources_.empty()) {
    std::string why;
    for (const auto& note : notes_) why += (why.empty() ? "" : "; ") + note;
    r.unavailable_reason = "no power source found: " + why;
  } else if (!r.available) {
    r.unavailable_reason = "no power source gave a measurement: " + failures;
  }
  return r;
}

PowerSampler::PowerSampler(PowerMeter& meter, std::chrono::nanoseconds period)
    : meter_(meter), period_(period) {
  if (period_.count() <= 0)
    throw std::invalid_argument("the power sampling period must be positive");
  thread_ = std::thread([this] { run(); });
}

PowerSampler::~PowerSampler() {
  if (thread_.joinable()) end();
}

void PowerSampler::on_window_edges(std::function<void(int64_t)> at_first,
                                   std::function<void(int64_t)> at_last) {
  std::lock_guard lock(mutex_);
  at_first_ = std::move(at_first);
  at_last_ = std::move(at_last);
}

void PowerSampler::begin() {
  std::lock_guard lock(mutex_);
  begun_ = true;
  cv_.notify_all();
}

PowerReport PowerSampler::end() {
  {
    std::lock_guard lock(mutex_);
    ending_ = true;
    cv_.notify_all();
  }
  if (thread_.joinable()) thread_.join();
  PowerReport r = meter_.report();
  r.period_s = std::chrono::duration<double>(period_).count();
  r.overruns = overruns_;
  r.sampler_cpu_s = cpu_s_;
  if (!begun_) {
    r.available = false;
    r.unavailable_reason = "the measured window never started (nothing was sent after the warm-up)";
  }
  return r;
}

void PowerSampler::run() {
  std::unique_lock lock(mutex_);
  cv_.wait(lock, [this] { return begun_ || ending_; });
  if (!begun_) return;
  const double cpu_start = thread_cpu_s();
  auto take_round = [&](const std::function<void(int64_t)>& edge) {
    lock.unlock();
    const int64_t now = steady_ns(std::chrono::steady_clock::now());
    meter_.sample_round(now);
    if (edge) edge(now);
    lock.lock();
  };
  auto next = std::chrono::steady_clock::now();
  take_round(at_first_);
  while (true) {
    next += period_;
    if (cv_.wait_until(lock, next, [this] { return ending_; })) break;
    take_round(nullptr);
    // Rounds that could not start on time are skipped, not bunched up.
    const auto now = std::chrono::steady_clock::now();
    while (next + period_ <= now) {
      next += period_;
      ++overruns_;
    }
  }
  take_round(at_last_);  // the end of the window
  cpu_s_ = thread_cpu_s() - cpu_start;
}

nlohmann::json to_json(const PowerReport& report, std::size_t messages, double throughput_hz) {
  using nlohmann::json;
  json sources = json::array();
  std::vector<std::string> in_total;
  for (const auto& s : report.sources) {
    if (s.available && s.info.in_total) in_total.push_back(s.info.name);
    sources.push_back({
        {"name", s.info.name},
        {"type", s.info.type},
        {"location", s.info.location},
        {"description", s.info.description},
        {"kind", kind_name(s.info.kind)},
        {"in_total", s.info.in_total},
        {"whole_machine", s.info.whole_machine},
        {"available", s.available},
        {"unavailable_reason", s.available ? json(nullptr) : json(s.unavailable_reason)},
        {"average_w", number_or_null(s.available, s.average_w)},
        {"energy_j", number_or_null(s.available, s.energy_j)},
        {"span_s", s.span_s},
        {"readings", s.readings},
        {"failed_readings", s.failed_readings},
        {"wraps", s.wraps},
        {"first_error", s.first_error.empty() ? json(nullptr) : json(s.first_error)},
        {"load", s.load ? json{{"readings", s.load->readings},
                               {"utilisation_mean_percent", s.load->utilisation_mean_percent},
                               {"utilisation_max_percent", s.load->utilisation_max_percent},
                               {"memory_used_max_bytes", s.load->memory_used_max_bytes},
                               {"memory_total_bytes", s.load->memory_total_bytes}}
                        : json(nullptr)},
    });
  }
  json total = nullptr;
  if (report.available) {
    total = {{"average_w", report.total_average_w},
             {"energy_j", report.total_energy_j},
             {"energy_per_message_mj",
              messages > 0 ? json(report.total_energy_j * 1e3 / static_cast<double>(messages))
                           : json(nullptr)},
             {"throughput_per_watt", throughput_hz > 0 && report.total_average_w > 0
                                         ? json(throughput_hz / report.total_average_w)
                                         : json(nullptr)},
             {"sources", in_total},
             {"estimated", report.estimated}};
  }
  return {
      {"available", report.available},
      {"unavailable_reason", report.available ? json(nullptr) : json(report.unavailable_reason)},
      {"total", total},
      {"sources", sources},
      {"period_s", report.period_s},
      {"window_s", report.window_s},
      {"rounds", report.rounds},
      {"overruns", report.overruns},
      {"sampler_cpu_s", report.sampler_cpu_s},
  };
}

nlohmann::json sources_to_json(const PowerDiscovery& discovery) {
  nlohmann::json sources = nlohmann::json::array();
  for (const auto& s : discovery.sources) {
    const auto& i = s->info();
    sources.push_back({{"name", i.name},
                       {"type", i.type},
                       {"location", i.location},
                       {"description", i.description},
                       {"kind", kind_name(i.kind)},
                       {"in_total", i.in_total},
                       {"whole_machine", i.whole_machine}});
  }
  return {{"sources", sources}, {"notes", discovery.notes}};
}

}  // namespace robotperf::metrics
