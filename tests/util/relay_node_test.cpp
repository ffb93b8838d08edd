// The util category's relay, which checks the harness: its parameters are bounded before use.
#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

#include "../node_test_support.hpp"
#include "robotperf/graph/node.hpp"
#include "robotperf/rmw/transport.hpp"

namespace robotperf::util {

void register_category(plugin::Registrar& registrar);

namespace {

const testing::CategoryUnderTest& category() {
  static const testing::CategoryUnderTest c{register_category};
  return c;
}

void build_relay(const std::string& delay_ms) {
  graph::Context context(rmw::make_transport("intra"));
  category().build(context, "util/relay",
                   category().config_of("util/relay", {{"delay_ms", delay_ms}}));
}

// An infinite, NaN or huge delay was converted to an integer first (undefined: on x86 it became
// a negative delay with a misleading message).
TEST(RelayNode, DelayIsBoundedBeforeItBecomesAnInteger) {
  EXPECT_NO_THROW(build_relay("20"));
  for (const char* delay : {"inf", "nan", "1e16", "-1"}) {
    try {
      build_relay(delay);
      ADD_FAILURE() << delay << " was accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("delay_ms must be from 0 to 3600000"), std::string::npos)
          << delay << ": " << e.what();
    }
  }
}

}  // namespace
}  // namespace robotperf::util
