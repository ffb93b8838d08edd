// Where the verbs that read runs (results list, compare, report) take them from: the folders or
// files named on the command line; else the PostgreSQL database --from names; else the one
// ROBOTPERF_RESULTS_URL names; else ./results (docs/reference/cli.md).
#pragma once

#include <filesystem>
#include <optional>
#include <string>

#include "robotperf/report/report.hpp"
#include "robotperf/report/run_store.hpp"
#include "robotperf/results_db/results_db.hpp"

namespace robotperf::cli {

// The database to read, when the runs come from one: `from` (--from), else ROBOTPERF_RESULTS_URL,
// unless `paths_named`: named folders and files come first (a --from beside them is said to be
// left aside, on stderr). Throws std::invalid_argument for a URL it refuses.
std::optional<std::string> database_to_read(const std::string& from, bool paths_named);

// The runs of the database at `url`, each run it cannot read a "skipped" line on stderr.
std::vector<report::StoredRun> runs_from_database(const std::string& url);

// The runs of a results folder (not its subfolders) as `results list` and `history` read them:
// through the folder's database, brought up to date with its files, when it has one (many runs
// listed without reading every file: docs/reference/results-database.md), else from the files.
// Files that cannot be read are "skipped" lines on stderr. Throws report::ReportError when the
// folder does not exist.
struct FolderRuns {
  std::vector<report::StoredRun> runs;
  std::optional<results_db::Synced> database;  // when the runs were listed from it
};
FolderRuns folder_runs(const std::filesystem::path& folder);

// Keeps the runs that carry every label of `labels` ("KEY=VALUE", as --label takes them): the
// read verbs' label filter.
void keep_labelled(std::vector<report::StoredRun>& runs, const std::vector<std::string>& labels);

// The same as the report's input: runs, no published rows.
report::ReportInput report_input_from_database(const std::string& url);

}  // namespace robotperf::cli
