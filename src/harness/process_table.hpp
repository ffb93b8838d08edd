// Private to the harness: the processes of this machine as /proc shows them, for the processes
// the harness starts that start processes of their own (`ros2 run`, `ros2 launch`, a wrapper
// script): their descendants are sampled and stopped with them.
#pragma once

#include <sys/types.h>

#include <cstdint>
#include <filesystem>
#include <vector>

namespace robotperf::harness {

// One line of /proc/<pid>/stat, the fields the harness needs.
struct ProcessEntry {
  pid_t pid = 0;
  char state = '?';  // 'Z': ended, waiting for its parent (or init) to reap it
  pid_t ppid = 0;
  pid_t pgrp = 0;
  // Since boot, in clock ticks: with the pid, it tells a process from a later one given its pid.
  uint64_t start_ticks = 0;
};

// Every process under `proc_root` (those that end while it is read are left out); empty when it
// cannot be read.
std::vector<ProcessEntry> list_processes(const std::filesystem::path& proc_root = "/proc");

// Whether any process of group `pgrp` still runs (is not a zombie) and can be signalled.
bool group_running(pid_t pgrp);

}  // namespace robotperf::harness
