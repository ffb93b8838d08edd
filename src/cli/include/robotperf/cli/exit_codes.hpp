// The exit codes of the robotperf command (documented in docs/reference/cli.md), and the one place that
// turns an error into its line on stderr and its code.
#pragma once

#include <exception>

namespace robotperf::cli {

constexpr int kExitOk = 0;
constexpr int kExitError = 1;
constexpr int kExitUsage = 2;
constexpr int kExitInvalidResult = 3;
constexpr int kExitRefused = 4;
// compare --fail-on-regression found a regression (1, as a failed check is in CI; bad input is 2).
constexpr int kExitRegression = 1;

// Prints "robotperf: <what>" for `error` and returns its exit code: kExitUsage for what the
// command line asked wrongly (a bad benchmark, bag, trace, plug-in, keystore, ...), kExitRefused
// for a run its rules refused, 128 + the signal for an interrupted run, kExitError otherwise.
int report_error(std::exception_ptr error);

}  // namespace robotperf::cli
