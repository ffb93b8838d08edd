// Linked into test programs declared with BUILTINS: registers the built-in categories before
// any test runs, as the robotperf executable does at start-up (from a test environment, so that
// it runs in main, after every static object is constructed).
#include <gtest/gtest.h>

#include "robotperf/categories/builtin.hpp"

namespace {

class BuiltinCategories final : public ::testing::Environment {
 public:
  void SetUp() override { robotperf::categories::register_builtin_categories(); }
};

const auto* const environment = ::testing::AddGlobalTestEnvironment(new BuiltinCategories);

}  // namespace
