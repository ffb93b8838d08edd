// Linked into the perception kernel tests that judge a backend's answers as a run does
// (harness::compare_answers): registers the perception category this program links, the real
// library or the one on the CUDA emulation, before any test runs. BUILTINS would link the real
// one beside the emulated one.
#include <gtest/gtest.h>

#include "robotperf/plugin/registry.hpp"

namespace robotperf::perception {
void register_category(plugin::Registrar& registrar);
}

namespace {

class PerceptionRegistered final : public ::testing::Environment {
 public:
  void SetUp() override {
    robotperf::plugin::registry().add("built-in perception",
                                      robotperf::perception::register_category);
  }
};

const auto* const environment = ::testing::AddGlobalTestEnvironment(new PerceptionRegistered);

}  // namespace
