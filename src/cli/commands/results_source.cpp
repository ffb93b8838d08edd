#include "results_source.hpp"

#include <algorithm>
#include <cstdio>
#include <cstdlib>

#include "robotperf/results_db/postgres_store.hpp"

namespace robotperf::cli {

std::optional<std::string> database_to_read(const std::string& from, bool paths_named) {
  if (paths_named) {
    if (!from.empty())
      std::fprintf(stderr, "robotperf: reading the results named; --from is left aside\n");
    return std::nullopt;
  }
  if (!from.empty()) return results_db::checked_url(from, "--from");
  const char* environment = std::getenv(results_db::kResultsUrlVariable);
  if (environment == nullptr || *environment == '\0') return std::nullopt;
  return results_db::checked_url(environment, results_db::kResultsUrlVariable);
}

std::vector<report::StoredRun> runs_from_database(const std::string& url) {
  report::RunScan scan = results_db::PostgresStore::connect(url).runs();
  for (const auto& s : scan.skipped) std::fprintf(stderr, "robotperf: skipped %s\n", s.c_str());
  return std::move(scan.runs);
}

FolderRuns folder_runs(const std::filesystem::path& folder) {
  FolderRuns out;
  out.database = results_db::open_synced(folder);
  if (out.database) {
    for (const auto& s : out.database->skipped)
      std::fprintf(stderr, "robotperf: skipped %s\n", s.c_str());
    out.runs = out.database->database.listed_runs();
    return out;
  }
  report::RunScan scan = report::scan_results(folder);
  for (const auto& s : scan.skipped) std::fprintf(stderr, "robotperf: skipped %s\n", s.c_str());
  out.runs = std::move(scan.runs);
  return out;
}

void keep_labelled(std::vector<report::StoredRun>& runs, const std::vector<std::string>& labels) {
  std::vector<std::pair<std::string, std::string>> wanted;
  for (const auto& label : labels) {
    const auto eq = label.find('=');
    wanted.emplace_back(label.substr(0, eq), label.substr(eq + 1));
  }
  std::erase_if(runs, [&](const report::StoredRun& run) {
    return !std::ranges::all_of(wanted, [&](const auto& w) {
      const auto it = run.labels.find(w.first);
      return it != run.labels.end() && it->second == w.second;
    });
  });
}

report::ReportInput report_input_from_database(const std::string& url) {
  return report::ReportInput{runs_from_database(url), {}, {}};
}

}  // namespace robotperf::cli
