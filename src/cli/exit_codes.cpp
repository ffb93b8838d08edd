#include "robotperf/cli/exit_codes.hpp"

#include <cstdio>
#include <stdexcept>

#include "interrupts.hpp"
#include "robotperf/bag/bag.hpp"
#include "robotperf/harness/benchmark_spec.hpp"
#include "robotperf/harness/network_link.hpp"
#include "robotperf/harness/run.hpp"
#include "robotperf/msgs/dynamic.hpp"
#include "robotperf/plugin/registry.hpp"
#include "robotperf/report/run_store.hpp"
#include "robotperf/results_db/postgres_store.hpp"
#include "robotperf/rmw/security.hpp"
#include "robotperf/tracing/ctf.hpp"
#include "robotperf/tracing/session.hpp"

namespace robotperf::cli {

namespace {

template <class... Errors>
bool is_one_of(const std::exception& error) {
  return (... || (dynamic_cast<const Errors*>(&error) != nullptr));
}

// What the user can fix on the command line, or in the files it names.
bool is_usage_error(const std::exception& error) {
  return is_one_of<plugin::PluginError, bag::BagError, msgs::dynamic::DefinitionError,
                   tracing::TracingUnavailable, tracing::ctf::CtfError, harness::BenchmarkError,
                   harness::GraphNotConnected, rmw::SecurityError, harness::NetworkSetupError,
                   report::ReportError, results_db::ConnectionError, std::invalid_argument>(error);
}

int exit_code(const std::exception& error) {
  if (is_one_of<harness::RunInterrupted>(error)) return interrupted_exit_code();
  if (is_one_of<harness::RunRefused>(error)) return kExitRefused;
  return is_usage_error(error) ? kExitUsage : kExitError;
}

}  // namespace

int report_error(std::exception_ptr error) {
  try {
    std::rethrow_exception(error);
  } catch (const std::exception& e) {
    const char* prefix = is_one_of<tracing::ctf::CtfError>(e) ? "unreadable trace: " : "";
    std::fprintf(stderr, "robotperf: %s%s\n", prefix, e.what());
    return exit_code(e);
  }
}

}  // namespace robotperf::cli
