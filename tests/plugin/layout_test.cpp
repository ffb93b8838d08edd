// The dependency rule of docs/design.md §1: the harness, cli and report name no kernel, dataset or
// evaluator; everything of a category lives in its folder and comes in through the plug-in API.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

#include "robotperf/categories/builtin.hpp"
#include "robotperf/plugin/registry.hpp"

namespace robotperf::plugin {
namespace {

namespace fs = std::filesystem;

const fs::path kSource = ROBOTPERF_SOURCE_DIR;

std::string read(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

std::vector<std::string> registered_names() {
  std::vector<std::string> names;
  for (const auto* e : registry().kernels()) names.push_back(e->info.name);
  for (const auto* e : registry().datasets()) names.push_back(e->info.name);
  for (const auto* e : registry().evaluators()) names.push_back(e->info.name);
  return names;
}

TEST(Layout, HarnessCliAndReportNameNoKernelDatasetOrEvaluator) {
  const auto names = registered_names();
  ASSERT_GT(names.size(), 20u);
  std::vector<std::string> found;
  for (const char* piece : {"src/harness", "src/cli", "src/report", "src/results_db"}) {
    for (const auto& f : fs::recursive_directory_iterator(kSource / piece)) {
      if (f.path().extension() != ".cpp" && f.path().extension() != ".hpp") continue;
      const std::string text = read(f.path());
      for (const auto& name : names) {
        // The name as a whole token: "collision" in "collision_checker" is not the evaluator.
        const std::regex token("(^|[^A-Za-z0-9_/])" +
                               std::regex_replace(name, std::regex("[/.]"), "\\$&") +
                               "($|[^A-Za-z0-9_/])");
        if (std::regex_search(text, token))
          found.push_back(fs::relative(f.path(), kSource).string() + " names " + name);
      }
    }
  }
  EXPECT_TRUE(found.empty()) << found.front();
}

TEST(Layout, EveryBuiltInEntryComesFromItsCategoryFolder) {
  std::vector<std::string> origins;
  for (const auto* e : registry().kernels()) origins.push_back(e->origin);
  for (const auto* e : registry().datasets()) origins.push_back(e->origin);
  for (const auto* e : registry().evaluators()) origins.push_back(e->origin);
  for (const auto& origin : origins) {
    if (!origin.starts_with("built-in ")) continue;  // a plug-in another test loaded
    const std::string category = origin.substr(9);
    EXPECT_TRUE(fs::is_directory(kSource / "src/categories" / category)) << origin;
  }
  for (const auto& category : categories::builtin_categories())
    EXPECT_TRUE(fs::exists(kSource / "src/categories" / category / "CMakeLists.txt")) << category;
  // Kernels and datasets live in their categories, not in libraries of their own.
  EXPECT_FALSE(fs::exists(kSource / "src/kernels"));
  EXPECT_FALSE(fs::exists(kSource / "src/datasets"));
}

}  // namespace
}  // namespace robotperf::plugin
