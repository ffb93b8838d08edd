// Where the verbs that read runs (results list, compare, report) take them from: the folders or
// files named on the command line; else the PostgreSQL database --from names; else the one
// ROBOTPERF_RESULTS_URL names; else ./results (docs/reference/cli.md).
#pragma once

#include <optional>
#include <string>

#include "robotperf/report/report.hpp"
#include "robotperf/report/run_store.hpp"

namespace robotperf::cli {

// The database to read, when the runs come from one: `from` (--from), else ROBOTPERF_RESULTS_URL,
// unless `paths_named`: named folders and files come first (a --from beside them is said to be
// left aside, on stderr). Throws std::invalid_argument for a URL it refuses.
std::optional<std::string> database_to_read(const std::string& from, bool paths_named);

// The runs of the database at `url`, each run it cannot read a "skipped" line on stderr.
std::vector<report::StoredRun> runs_from_database(const std::string& url);

// The same as the report's input: runs, no published rows.
report::ReportInput report_input_from_database(const std::string& url);

}  // namespace robotperf::cli
