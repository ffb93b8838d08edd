#include "robotperf/harness/scheduling.hpp"

#include <sys/mman.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <stdexcept>

namespace robotperf::harness {
namespace {

unsigned parse_cpu(const std::string& text, const std::string& whole) {
  if (text.empty() || text.find_first_not_of("0123456789") != std::string::npos ||
      text.size() > 5) {
    throw std::invalid_argument("bad CPU list '" + whole + "': '" + text +
                                "' is not a CPU number (expected e.g. 2-3 or 0,2,4)");
  }
  const unsigned cpu = static_cast<unsigned>(std::stoul(text));
  if (cpu >= CPU_SETSIZE) throw std::invalid_argument("CPU " + text + " is out of range");
  return cpu;
}

}  // namespace

std::vector<std::string> SchedulingOptions::node_arguments() const {
  std::vector<std::string> args;
  if (!cpus.empty()) args.insert(args.end(), {"--cpus", format_cpu_list(cpus)});
  if (rt_priority != 0) args.insert(args.end(), {"--rt-priority", std::to_string(rt_priority)});
  if (lock_memory) args.push_back("--mlock");
  return args;
}

std::vector<unsigned> parse_cpu_list(const std::string& text) {
  std::vector<unsigned> cpus;
  std::size_t start = 0;
  while (start <= text.size()) {
    const auto comma = text.find(',', start);
    const std::string range =
        text.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    const auto dash = range.find('-');
    const unsigned first = parse_cpu(range.substr(0, dash), text);
    const unsigned last =
        dash == std::string::npos ? first : parse_cpu(range.substr(dash + 1), text);
    if (last < first) throw std::invalid_argument("bad CPU list '" + text + "': " + range);
    for (unsigned cpu = first; cpu <= last; ++cpu) {
      if (std::find(cpus.begin(), cpus.end(), cpu) == cpus.end()) cpus.push_back(cpu);
    }
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  std::sort(cpus.begin(), cpus.end());
  return cpus;
}

std::string format_cpu_list(const std::vector<unsigned>& cpus) {
  std::string out;
  for (std::size_t i = 0; i < cpus.size();) {
    std::size_t j = i;
    while (j + 1 < cpus.size() && cpus[j + 1] == cpus[j] + 1) ++j;
    out += (out.empty() ? "" : ",") + std::to_string(cpus[i]);
    if (j > i) out += "-" + std::to_string(cpus[j]);
    i = j + 1;
  }
  return out;
}

std::vector<unsigned> allowed_cpus() {
  cpu_set_t set;
  CPU_ZERO(&set);
  if (sched_getaffinity(0, sizeof set, &set) != 0)
    throw std::runtime_error(std::string("sched_getaffinity: ") + std::strerror(errno));
  std::vector<unsigned> cpus;
  for (unsigned cpu = 0; cpu < CPU_SETSIZE; ++cpu) {
    if (CPU_ISSET(cpu, &set)) cpus.push_back(cpu);
  }
  return cpus;
}

void check_cpus_allowed(const std::vector<unsigned>& cpus) {
  const auto allowed = allowed_cpus();
  std::vector<unsigned> missing;
  for (unsigned cpu : cpus) {
    if (!std::binary_search(allowed.begin(), allowed.end(), cpu)) missing.push_back(cpu);
  }
  if (missing.empty()) return;
  throw std::invalid_argument(
      "--cpus: CPU " + format_cpu_list(missing) + " " + (missing.size() == 1 ? "is" : "are") +
      " not available to this process (it may run on " + format_cpu_list(allowed) + ")");
}

ScopedScheduling::ScopedScheduling(const SchedulingOptions& options) {
  try {
    if (!options.cpus.empty()) {
      check_cpus_allowed(options.cpus);
      if (sched_getaffinity(0, sizeof affinity_, &affinity_) != 0) {
        throw std::runtime_error(std::string("sched_getaffinity: ") + std::strerror(errno));
      }
      cpu_set_t wanted;
      CPU_ZERO(&wanted);
      for (const unsigned cpu : options.cpus) CPU_SET(cpu, &wanted);
      if (sched_setaffinity(0, sizeof wanted, &wanted) != 0) {
        throw std::runtime_error("cannot pin to CPUs " + format_cpu_list(options.cpus) + ": " +
                                 std::strerror(errno) +
                                 " (are they online and allowed to this process? see nproc)");
      }
      restore_affinity_ = true;
    }
    if (options.rt_priority != 0) {
      if (options.rt_priority < 1 || options.rt_priority > 99) {
        throw std::invalid_argument("--rt-priority must be within 1-99");
      }
      policy_ = sched_getscheduler(0);
      sched_getparam(0, &param_);
      sched_param wanted{};
      wanted.sched_priority = options.rt_priority;
      if (sched_setscheduler(0, SCHED_FIFO, &wanted) != 0) {
        throw std::runtime_error("cannot run with real-time priority " +
                                 std::to_string(options.rt_priority) + ": " + std::strerror(errno) +
                                 " (needs root, CAP_SYS_NICE or an rtprio limit in "
                                 "/etc/security/limits.conf)");
      }
      restore_policy_ = true;
    }
    if (options.lock_memory) {
      if (mlockall(MCL_CURRENT | MCL_FUTURE) != 0) {
        throw std::runtime_error(std::string("cannot lock memory: ") + std::strerror(errno) +
                                 " (needs root, CAP_IPC_LOCK or a larger memlock limit: "
                                 "ulimit -l)");
      }
      unlock_memory_ = true;
    }
  } catch (...) {
    restore();
    throw;
  }
}

ScopedScheduling::~ScopedScheduling() {
  restore();
}

void ScopedScheduling::restore() {
  if (unlock_memory_) munlockall();
  if (restore_policy_) sched_setscheduler(0, policy_, &param_);
  if (restore_affinity_) sched_setaffinity(0, sizeof affinity_, &affinity_);
  unlock_memory_ = restore_policy_ = restore_affinity_ = false;
}

}  // namespace robotperf::harness
