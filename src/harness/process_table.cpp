#include "process_table.hpp"

#include <signal.h>

#include <algorithm>
#include <charconv>
#include <fstream>
#include <sstream>
#include <string>
#include <system_error>

namespace robotperf::harness {

std::vector<ProcessEntry> list_processes(const std::filesystem::path& proc_root) {
  std::vector<ProcessEntry> out;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(proc_root, ec)) {
    const std::string name = entry.path().filename().string();
    ProcessEntry p;
    if (std::from_chars(name.data(), name.data() + name.size(), p.pid).ptr !=
        name.data() + name.size())
      continue;
    std::ifstream in(entry.path() / "stat");
    std::string stat;
    if (!std::getline(in, stat)) continue;  // ended meanwhile
    // The command name (field 2) may hold spaces and parentheses: fields restart after the last
    // ')'. Then: state, ppid, pgrp, ... starttime (field 22).
    const auto close = stat.rfind(')');
    if (close == std::string::npos) continue;
    std::istringstream fields(stat.substr(close + 1));
    std::string skip;
    fields >> p.state >> p.ppid >> p.pgrp;
    for (int field = 6; field < 22; ++field) fields >> skip;
    fields >> p.start_ticks;
    if (fields) out.push_back(p);
  }
  return out;
}

bool group_running(pid_t pgrp) {
  // Cheap first: no member at all. A zombie still counts for kill(), hence the list.
  if (pgrp <= 0 || kill(-pgrp, 0) != 0) return false;
  return std::ranges::any_of(list_processes(), [&](const ProcessEntry& p) {
    return p.pgrp == pgrp && p.state != 'Z' && p.state != 'X';
  });
}

}  // namespace robotperf::harness
