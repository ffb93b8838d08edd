// The read verbs over a results folder of 10,000 runs (a lab's months: 8 boards, both transports),
// as a user runs them: `results list`, `history` and `compare`, each timed as the robotperf
// command it is, with the folder's database in place (runs record into it) and, for reference,
// without it. Run on demand: ./build/bench/results_db/bench_results_read
//
// Target (issue 48): each answers in under 1 s with the database. Exit status 1 when one does
// not.
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <string>

#include "report/sample_runs.hpp"
#include "robotperf/results_db/results_db.hpp"
#include "this_build.hpp"

namespace fs = std::filesystem;
using namespace robotperf;

namespace {

constexpr int kRuns = 10'000;
constexpr double kTargetS = 1;

// Runs `command` (output discarded), and returns its wall time in seconds; throws when it fails.
double timed(const std::string& command) {
  const auto start = std::chrono::steady_clock::now();
  const int status = std::system((command + " > /dev/null").c_str());
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (status == -1 || !WIFEXITED(status) || WEXITSTATUS(status) != 0)
    throw std::runtime_error(command + ": failed");
  return s;
}

int read_a_labs_months() {
  bench::warn_about_this_build();
  const fs::path dir =
      fs::temp_directory_path() / ("robotperf-bench-read-" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  struct Cleanup {
    fs::path dir;
    ~Cleanup() { fs::remove_all(dir); }
  } cleanup{dir};
  for (int k = 0; k < kRuns; ++k) {
    report::testing::SampleRun s;
    s.start_unix_ns += static_cast<int64_t>(k) * 60'000'000'000;  // a run a minute
    // 8 boards, each with both transports: 16 configurations of 625 runs, slower from the
    // middle of the months on.
    s.base_latency_ms = (k < kRuns / 2 ? 2.0 : 2.4) * (1.0 + 0.01 * (k % 7));
    s.rmw = (k / 8) % 2 ? "intra" : "fastdds";
    s.cpu = "Board CPU model " + std::to_string(k % 8);
    report::testing::write_sample(dir, s);
  }
  const std::string robotperf = ROBOTPERF_EXECUTABLE;
  const std::string list = robotperf + " results list " + dir.string();
  const std::string history = robotperf + " history a1 --results " + dir.string();
  const std::string compare = robotperf +
                              " compare 'hardware=Board CPU model 0,rmw=intra' "
                              "'hardware=Board CPU model 0,rmw=fastdds' --results " +
                              dir.string();
  std::printf("%d runs in %s\n", kRuns, dir.c_str());
  std::printf("without the database (every file read):\n");
  const double list_files = timed(list), history_files = timed(history),
               compare_files = timed(compare);
  std::printf("  results list %.2f s, history %.2f s, compare %.2f s\n", list_files, history_files,
              compare_files);
  const auto rebuilt = results_db::rebuild(dir);
  std::printf("with the database (%zu runs recorded):\n", rebuilt.recorded);
  bool met = true;
  for (const auto& [name, command] :
       {std::pair{"results list", list}, std::pair{"history", history},
        std::pair{"compare", compare}}) {
    const double s = timed(command);
    met = met && s < kTargetS;
    std::printf("  %-12s %.2f s: %.2f of the %.0f s target\n", name, s, s / kTargetS, kTargetS);
  }
  return met ? 0 : 1;
}

}  // namespace

int main() {
  try {
    return read_a_labs_months();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_results_read: %s\n", e.what());
    return 2;
  }
}
