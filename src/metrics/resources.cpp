#include "robotperf/metrics/resources.hpp"

#include <unistd.h>

#include <algorithm>
#include <fstream>
#include <sstream>
#include <system_error>

namespace robotperf::metrics {
namespace {

namespace fs = std::filesystem;

std::optional<std::string> read_file(const fs::path& path) {
  std::ifstream in(path);
  if (!in) return std::nullopt;
  std::ostringstream content;
  content << in.rdbuf();
  return std::move(content).str();
}

double ticks_per_second() {
  static const double hz = [] {
    const long v = ::sysconf(_SC_CLK_TCK);
    return v > 0 ? static_cast<double>(v) : 100.0;
  }();
  return hz;
}

// "Key:   value kB" lines of /proc/<pid>/status.
std::optional<uint64_t> status_value(const std::string& status, const std::string& key) {
  std::istringstream lines(status);
  std::string line;
  while (std::getline(lines, line)) {
    if (line.rfind(key + ":", 0) != 0) continue;
    std::istringstream fields(line.substr(key.size() + 1));
    uint64_t value = 0;
    if (fields >> value) return value;
    return std::nullopt;
  }
  return std::nullopt;
}

}  // namespace

ProcessSnapshot read_process(const fs::path& proc_root, int pid) {
  ProcessSnapshot s;
  const fs::path dir = proc_root / std::to_string(pid);
  const auto stat = read_file(dir / "stat");
  if (!stat) {
    s.error = "cannot read " + (dir / "stat").string() + " (process gone?)";
    return s;
  }
  // The command name (field 2) may hold spaces and parentheses: fields restart after the last ')'.
  const auto close = stat->rfind(')');
  if (close == std::string::npos) {
    s.error = (dir / "stat").string() + ": malformed";
    return s;
  }
  std::istringstream fields(stat->substr(close + 1));
  std::vector<std::string> f;  // f[0] is field 3 (state)
  for (std::string token; fields >> token && f.size() < 20;) f.push_back(token);
  if (f.size() < 13) {
    s.error = (dir / "stat").string() + ": too few fields";
    return s;
  }
  const auto field = [&f](int number) {
    return std::stoull(f[static_cast<std::size_t>(number - 3)]);
  };
  try {
    s.minor_faults = field(10);
    s.major_faults = field(12);
    s.cpu_user_s = static_cast<double>(field(14)) / ticks_per_second();
    s.cpu_system_s = static_cast<double>(field(15)) / ticks_per_second();
  } catch (const std::exception&) {
    s.error = (dir / "stat").string() + ": malformed";
    return s;
  }
  const auto status = read_file(dir / "status").value_or("");
  if (const auto hwm = status_value(status, "VmHWM")) s.peak_rss_bytes = *hwm * 1024;
  // Context switches in status are per thread: add up those of every thread.
  std::error_code ec;
  bool any_task = false;
  for (const auto& task : fs::directory_iterator(dir / "task", ec)) {
    const auto task_status = read_file(task.path() / "status");
    if (!task_status) continue;
    any_task = true;
    s.voluntary_switches += status_value(*task_status, "voluntary_ctxt_switches").value_or(0);
    s.involuntary_switches += status_value(*task_status, "nonvoluntary_ctxt_switches").value_or(0);
  }
  if (!any_task) {
    s.voluntary_switches = status_value(status, "voluntary_ctxt_switches").value_or(0);
    s.involuntary_switches = status_value(status, "nonvoluntary_ctxt_switches").value_or(0);
  }
  s.ok = true;
  return s;
}

SystemCpuSnapshot read_system_cpu(const fs::path& proc_root) {
  SystemCpuSnapshot s;
  const auto stat = read_file(proc_root / "stat");
  if (!stat) return s;
  std::istringstream lines(*stat);
  std::string line;
  while (std::getline(lines, line)) {
    if (line.rfind("cpu", 0) != 0) continue;
    std::istringstream fields(line);
    std::string name;
    fields >> name;
    // user nice system idle iowait irq softirq steal (guest time is already inside user).
    uint64_t v[8] = {};
    for (auto& x : v) fields >> x;
    CpuTicks t;
    t.busy = v[0] + v[1] + v[2] + v[5] + v[6] + v[7];
    t.total = t.busy + v[3] + v[4];
    if (name == "cpu") {
      s.all = t;
      s.ok = true;
    } else {
      try {
        s.cpu_ids.push_back(static_cast<unsigned>(std::stoul(name.substr(3))));
        s.per_cpu.push_back(t);
      } catch (const std::exception&) {
      }
    }
  }
  return s;
}

ResourceMonitor::ResourceMonitor(fs::path proc_root, std::vector<Process> processes)
    : proc_root_(std::move(proc_root)), processes_(std::move(processes)) {}

void ResourceMonitor::begin(int64_t now_ns) {
  first_.clear();
  for (const auto& p : processes_) first_.push_back(read_process(proc_root_, p.pid));
  system_first_ = read_system_cpu(proc_root_);
  begin_ns_ = now_ns;
}

void ResourceMonitor::end(int64_t now_ns) {
  last_.clear();
  for (const auto& p : processes_) last_.push_back(read_process(proc_root_, p.pid));
  system_last_ = read_system_cpu(proc_root_);
  end_ns_ = now_ns;
}

ResourceUsage ResourceMonitor::usage() const {
  ResourceUsage u;
  if (begin_ns_ < 0 || end_ns_ <= begin_ns_) return u;
  u.measured = true;
  u.window_s = static_cast<double>(end_ns_ - begin_ns_) * 1e-9;
  double graph_cpu_s = 0;
  bool all_processes_measured = true;
  for (std::size_t i = 0; i < processes_.size(); ++i) {
    ProcessUsage p;
    p.label = processes_[i].label;
    p.pid = processes_[i].pid;
    const auto& a = first_[i];
    const auto& b = last_[i];
    if (!a.ok || !b.ok) {
      p.error = !a.ok ? a.error : b.error;
      all_processes_measured = false;
      u.processes.push_back(std::move(p));
      continue;
    }
    p.measured = true;
    p.cpu_user_s = b.cpu_user_s - a.cpu_user_s;
    p.cpu_system_s = b.cpu_system_s - a.cpu_system_s;
    p.cpu_percent = 100.0 * (p.cpu_user_s + p.cpu_system_s) / u.window_s;
    p.peak_rss_bytes = b.peak_rss_bytes;
    // Counters of threads that ended inside the window are gone: never report a negative delta.
    const auto delta = [](uint64_t x, uint64_t y) { return y >= x ? y - x : 0; };
    p.voluntary_switches = delta(a.voluntary_switches, b.voluntary_switches);
    p.involuntary_switches = delta(a.involuntary_switches, b.involuntary_switches);
    p.minor_faults = delta(a.minor_faults, b.minor_faults);
    p.major_faults = delta(a.major_faults, b.major_faults);
    graph_cpu_s += p.cpu_user_s + p.cpu_system_s;
    u.processes.push_back(std::move(p));
  }
  if (system_first_.ok && system_last_.ok) {
    const auto busy_percent = [](const CpuTicks& a, const CpuTicks& b) {
      const uint64_t total = b.total - a.total;
      return total > 0 ? 100.0 * static_cast<double>(b.busy - a.busy) / static_cast<double>(total)
                       : 0.0;
    };
    u.system_busy_percent = busy_percent(system_first_.all, system_last_.all);
    if (system_first_.cpu_ids == system_last_.cpu_ids) {
      u.cpu_ids = system_last_.cpu_ids;
      for (std::size_t i = 0; i < system_last_.per_cpu.size(); ++i) {
        u.per_cpu_busy_percent.push_back(
            busy_percent(system_first_.per_cpu[i], system_last_.per_cpu[i]));
      }
    }
    if (all_processes_measured) {
      const double system_busy_s =
          static_cast<double>(system_last_.all.busy - system_first_.all.busy) / ticks_per_second();
      u.other_cpu_percent = std::max(0.0, 100.0 * (system_busy_s - graph_cpu_s) / u.window_s);
    }
  }
  return u;
}

nlohmann::json to_json(const ResourceUsage& u) {
  using nlohmann::json;
  if (!u.measured) return {{"measured", false}};
  json processes = json::array();
  for (const auto& p : u.processes) {
    json j = {{"label", p.label}, {"pid", p.pid}, {"measured", p.measured}};
    if (!p.measured) {
      j["error"] = p.error;
    } else {
      j.update({{"cpu_user_s", p.cpu_user_s},
                {"cpu_system_s", p.cpu_system_s},
                {"cpu_percent", p.cpu_percent},
                {"peak_rss_bytes", p.peak_rss_bytes ? json(*p.peak_rss_bytes) : json(nullptr)},
                {"voluntary_context_switches", p.voluntary_switches},
                {"involuntary_context_switches", p.involuntary_switches},
                {"minor_page_faults", p.minor_faults},
                {"major_page_faults", p.major_faults}});
    }
    processes.push_back(std::move(j));
  }
  json per_cpu = json::array();
  for (std::size_t i = 0; i < u.per_cpu_busy_percent.size(); ++i) {
    per_cpu.push_back({{"cpu", u.cpu_ids[i]}, {"busy_percent", u.per_cpu_busy_percent[i]}});
  }
  const auto optional = [](const std::optional<double>& v) { return v ? json(*v) : json(nullptr); };
  return {{"measured", true},
          {"window_s", u.window_s},
          {"processes", processes},
          {"system",
           {{"busy_percent", optional(u.system_busy_percent)},
            {"other_processes_cpu_percent", optional(u.other_cpu_percent)},
            {"per_cpu", per_cpu}}}};
}

}  // namespace robotperf::metrics
