// `results push` of a fleet's day: 1,000 runs (one in ten with its per-message latencies) read
// from their files and pushed into a new PostgreSQL database, on a server started here with fsync
// on, as a lab's has it. Run on demand: ./build/bench/results_db/bench_results_push
//
// Target (issue 48): 1,000 runs in 10 s or less. Exit status 1 when over it.
#include <chrono>
#include <cstdio>
#include <exception>
#include <filesystem>

#include "report/sample_runs.hpp"
#include "results_db/postgres_server.hpp"
#include "robotperf/report/run_store.hpp"
#include "robotperf/results_db/postgres_store.hpp"
#include "this_build.hpp"

namespace fs = std::filesystem;
using namespace robotperf;

namespace {

constexpr int kRuns = 1000;
constexpr double kTargetS = 10;

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

int push_a_fleets_day() {
  bench::warn_about_this_build();
  if (test_support::postgres_bin_dir().empty()) {
    std::fprintf(stderr, "bench_results_push: no PostgreSQL server in /usr/lib/postgresql/*/bin\n");
    return 2;
  }
  test_support::PostgresServer server(/*durable=*/true);
  server.create_database("fleet");
  const fs::path dir = server.dir() / "results";
  fs::create_directories(dir);
  for (int k = 0; k < kRuns; ++k) {
    report::testing::SampleRun s;
    s.start_unix_ns += static_cast<int64_t>(k) * 1'000'000'000;
    s.base_latency_ms = 2.0 + k % 13;
    s.rmw = k % 2 ? "intra" : "fastdds";
    s.labels = {{"board", "board-" + std::to_string(k % 8)}};
    report::testing::write_sample(dir, s, /*csv=*/k % 10 == 0);
  }

  const auto start = std::chrono::steady_clock::now();
  const report::RunScan scan = report::scan_results(dir);
  const double read_s = seconds_since(start);
  auto store = results_db::PostgresStore::connect(server.socket_url("fleet"));
  const results_db::Pushed pushed = store.push(scan.runs);
  const double total_s = seconds_since(start);

  const auto rows =
      server.query("fleet",
                   "SELECT (SELECT count(*) FROM runs), (SELECT count(*) FROM metrics), "
                   "(SELECT count(*) FROM samples), (SELECT count(*) FROM histogram)");
  std::printf(
      "pushed %zu runs (%s runs, %s metrics, %s samples, %s histogram bins in the "
      "database)\n",
      pushed.pushed, rows[0][0].c_str(), rows[0][1].c_str(), rows[0][2].c_str(),
      rows[0][3].c_str());
  std::printf(
      "time: %.2f s (reading the files %.2f s, connecting and pushing %.2f s): %.2f of "
      "the %.0f s target\n",
      total_s, read_s, total_s - read_s, total_s / kTargetS, kTargetS);
  if (pushed.pushed != static_cast<std::size_t>(kRuns)) {
    std::fprintf(stderr, "bench_results_push: %zu runs pushed, not %d\n", pushed.pushed, kRuns);
    return 1;
  }
  return total_s <= kTargetS ? 0 : 1;
}

}  // namespace

int main() {
  try {
    return push_a_fleets_day();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_results_push: %s\n", e.what());
    return 2;
  }
}
