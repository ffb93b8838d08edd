// Runs command lines for the end-to-end tests, as a user's shell would.
#pragma once

#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <string>

namespace robotperf::test_support {

struct Outcome {
  int exit_code = -1;  // -1 when the command did not exit normally
  std::string out;     // stdout and stderr together
};

inline Outcome shell(const std::string& command) {
  Outcome o;
  FILE* p = popen((command + " 2>&1").c_str(), "r");
  if (p == nullptr) return o;
  std::array<char, 4096> buf;
  while (std::size_t n = fread(buf.data(), 1, buf.size(), p)) o.out.append(buf.data(), n);
  const int status = pclose(p);
  o.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return o;
}

#ifdef ROBOTPERF_EXECUTABLE
// The robotperf under test with `args`; `environment` (VAR=value ...) goes before it.
inline Outcome robotperf_cli(const std::string& args, const std::string& environment = "") {
  return shell(environment + " " + ROBOTPERF_EXECUTABLE + " " + args);
}
#endif

}  // namespace robotperf::test_support
