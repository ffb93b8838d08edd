// `run --backend` refusals come from the backend's registered entry, whoever registered it.
#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

#include "robotperf/harness/backend_check.hpp"
#include "robotperf/plugin/registry.hpp"

namespace robotperf::harness {
namespace {

TEST(BackendAvailable, ABackendThisBuildLacksIsRefusedWithItsLine) {
  plugin::registry().add("backend_available_test", [](plugin::Registrar& r) {
    r.add_backend({"backend_available_test_unbuilt", "never built"},
                  {.devices = {}, .unavailable_reason = [] { return std::string("not built"); }});
    r.add_backend({"backend_available_test_built", "always there"},
                  {.devices = {}, .unavailable_reason = [] { return std::string(); }});
    r.add_backend({"backend_available_test_plain", "no hooks"}, {});
  });
  try {
    check_backend_available("backend_available_test_unbuilt");
    ADD_FAILURE() << "not refused";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "--backend backend_available_test_unbuilt: not built");
  }
  EXPECT_NO_THROW(check_backend_available("backend_available_test_built"));
  EXPECT_NO_THROW(check_backend_available("backend_available_test_plain"));
  // Left to override_backend, which names the backends the kernels have.
  EXPECT_NO_THROW(check_backend_available("cpu"));
  EXPECT_NO_THROW(check_backend_available("no_such_backend"));
}

}  // namespace
}  // namespace robotperf::harness
