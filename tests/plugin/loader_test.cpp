// Loading plug-ins: one that works, its kernel, dataset and evaluator run through the harness as
// the built-in ones do; and each way a plug-in can fail to load gives one line naming the file.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "../harness/test_package.hpp"
#include "robotperf/harness/run.hpp"
#include "robotperf/msgs/sensor_msgs.hpp"
#include "robotperf/plugin/registry.hpp"
#include "robotperf/plugin/version.hpp"
#include "robotperf/rmw/transport.hpp"

namespace robotperf::plugin {
namespace {

namespace fs = std::filesystem;

std::string load_error(const fs::path& file) {
  try {
    registry().load(file);
  } catch (const PluginError& e) {
    return e.what();
  }
  return "";
}

TEST(PluginLoader, LoadsAPluginOnceWithItsOrigin) {
  registry().load(GOOD_PLUGIN);
  registry().load(GOOD_PLUGIN);  // again: nothing happens
  const std::string canonical = fs::canonical(GOOD_PLUGIN).string();
  EXPECT_EQ(std::ranges::count(registry().plugins(), fs::path(canonical)), 1);
  const KernelEntry* k = registry().find_kernel("test_plugin/scale");
  ASSERT_NE(k, nullptr);
  EXPECT_EQ(k->origin, canonical);
  EXPECT_EQ(k->info.backends, (std::vector<std::string>{"cpu", "test_backend"}));
  EXPECT_NE(registry().find_dataset("test_plugin/joints"), nullptr);
  EXPECT_NE(registry().find_evaluator("test_plugin/scaled"), nullptr);
  // A message type has one TypeSupport in the process, whichever module asks for it: the
  // plug-in's dataset and this test's code agree on it.
  const harness::Dataset d = harness::load_dataset("test_plugin/joints");
  EXPECT_EQ(d.stream("states").type, &msgs::type_support<msgs::JointState>());
  // The built-in categories are there beside it.
  EXPECT_EQ(registry().find_kernel("util/relay")->origin, "built-in util");
}

TEST(PluginLoader, AFileThatIsNotThereIsNamed) {
  const std::string e = load_error("/nonexistent/libmissing.so");
  EXPECT_EQ(e, "plug-in /nonexistent/libmissing.so: file not found");
}

TEST(PluginLoader, AFileThatIsNotASharedLibraryIsRefused) {
  const fs::path text = fs::temp_directory_path() / ("robotperf-text-" + std::to_string(getpid()));
  std::ofstream(text) << "not an ELF file\n";
  const std::string e = load_error(text);
  fs::remove(text);
  EXPECT_NE(e.find("plug-in " + text.string()), std::string::npos) << e;
  EXPECT_NE(e.find("cannot be loaded as a shared library"), std::string::npos) << e;
}

TEST(PluginLoader, ASharedLibraryWithoutEntryPointsIsNotAPlugin) {
  const std::string e = load_error(NOT_A_PLUGIN);
  EXPECT_NE(e.find(fs::canonical(NOT_A_PLUGIN).string()), std::string::npos) << e;
  EXPECT_NE(e.find("not a robotperf plug-in"), std::string::npos) << e;
}

TEST(PluginLoader, AnotherApiVersionIsRefused) {
  const std::string e = load_error(VERSION_MISMATCH_PLUGIN);
  EXPECT_NE(e.find("built against plug-in API version " +
                   std::to_string(ROBOTPERF_PLUGIN_API_VERSION + 1)),
            std::string::npos)
      << e;
  EXPECT_NE(e.find("rebuild it against this robotperf"), std::string::npos) << e;
}

// Its version is read from the file: loading it would fail on the missing symbol, and its code
// would run.
TEST(PluginLoader, AnOlderApiVersionIsRefusedBeforeItIsLoaded) {
  const std::string e = load_error(OLD_API_PLUGIN);
  EXPECT_NE(e.find("built against plug-in API version " +
                   std::to_string(ROBOTPERF_PLUGIN_API_VERSION - 1) + ", this robotperf has"),
            std::string::npos)
      << e;
}

TEST(PluginLoader, ANameTakenByABuiltInCategoryIsRefused) {
  const std::string e = load_error(DUPLICATE_PLUGIN);
  EXPECT_NE(e.find(fs::canonical(DUPLICATE_PLUGIN).string()), std::string::npos) << e;
  EXPECT_NE(e.find("kernel 'util/relay' is already registered by built-in util"), std::string::npos)
      << e;
  EXPECT_EQ(registry().find_kernel("util/relay")->origin, "built-in util");
}

TEST(PluginLoader, APluginThatThrowsWhileRegisteringLeavesNothing) {
  const std::string e = load_error(THROWING_PLUGIN);
  EXPECT_NE(e.find("registration failed: no licence for this accelerator"), std::string::npos) << e;
  EXPECT_EQ(registry().find_kernel("throwing_plugin/kept_nowhere"), nullptr);
  EXPECT_EQ(std::ranges::count(registry().plugins(), fs::canonical(THROWING_PLUGIN)), 0);
}

std::string plugin_graph(const std::string& plugins_line, const std::string& evaluator_extra) {
  return plugins_line +
         "dataset: test_plugin/joints\n"
         "rate_hz: 100\n"
         "warmup: 2\n"
         "validity: {min_samples: 10, max_loss_percent: 0.0}\n"
         "inputs:\n"
         "  - {topic: /states, type: sensor_msgs/msg/JointState, stream: states}\n"
         "output: {topic: /scaled, type: sensor_msgs/msg/JointState}\n"
         "nodes:\n"
         "  - name: scale\n"
         "    kernel: test_plugin/scale\n"
         "    parameters: {factor: 2.0}\n"
         "    topics: {input: /states, output: /scaled}\n"
         "functional:\n"
         "  evaluator: test_plugin/scaled\n"
         "  truth: {scaled: scaled}\n"
         "  sample: 0\n" +
         evaluator_extra;
}

harness::RunOptions quick() {
  harness::RunOptions o;
  o.load.count = 30;
  o.load.rate_hz = 100;
  o.transport.domain_id = rmw::reserved_domain();
  return o;
}

TEST(PluginLoader, APackageLoadsItsPluginsAndRunsTheirKernelDatasetAndEvaluator) {
  // `plugins:` relative to the package folder. A link, not a copy: the registry knows a plug-in
  // by its real path, and other tests of this process may have loaded this one already.
  harness::testing::TestPackage package("plugin", "");
  fs::create_symlink(GOOD_PLUGIN, package.dir() / "libgood.so");
  std::ofstream(package.dir() / "graph.yaml") << plugin_graph("plugins: [libgood.so]\n", "");
  const harness::BenchmarkSpec spec = harness::load_benchmark(package.dir());
  ASSERT_EQ(spec.plugins.size(), 1u);
  const harness::RunResult r = harness::run_benchmark(spec, quick());
  EXPECT_TRUE(r.valid) << (r.invalid_reasons.empty() ? "" : r.invalid_reasons.front());
  EXPECT_EQ(r.matched, 28u);
  ASSERT_TRUE(r.functional.has_value());
  EXPECT_TRUE(r.functional->valid);
  EXPECT_EQ(r.functional->evaluated, 28u);
  EXPECT_EQ(r.functional->metrics.at(0).value, 1.0);
  EXPECT_EQ(r.dataset_parameters.at("seed"), "7");
  EXPECT_EQ(r.nodes.at(0).counters.at("scaled"), 30u);
}

TEST(PluginLoader, AnEvaluatorParameterChangesTheVerdict) {
  registry().load(GOOD_PLUGIN);
  // The kernel scales by 3 while the truth is scaled by 2: a wrong answer, found as such.
  harness::testing::TestPackage package("plugin_wrong", "");
  std::string graph = plugin_graph("", "  parameters: {tolerance: 0.5}\n");
  graph.replace(graph.find("factor: 2.0"), 11, "factor: 3.0");
  std::ofstream(package.dir() / "graph.yaml") << graph;
  std::ofstream(package.dir() / "benchmark.yaml", std::ios::app)
      << "functional:\n  thresholds:\n    match_fraction: {min: 1.0}\n";
  const harness::RunResult r =
      harness::run_benchmark(harness::load_benchmark(package.dir()), quick());
  ASSERT_TRUE(r.functional.has_value());
  EXPECT_FALSE(r.functional->valid);
  EXPECT_LT(r.functional->metrics.at(0).value, 1.0);
}

TEST(PluginLoader, APackageNamingABrokenPluginFailsNamingTheLine) {
  harness::testing::TestPackage package("plugin_broken", "");
  std::ofstream(package.dir() / "graph.yaml")
      << plugin_graph("plugins:\n  - " + std::string(VERSION_MISMATCH_PLUGIN) + "\n", "");
  try {
    harness::load_benchmark(package.dir());
    FAIL() << "loaded a package whose plug-in cannot be loaded";
  } catch (const harness::BenchmarkError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("graph.yaml:2: plug-in"), std::string::npos) << what;
    EXPECT_NE(what.find("API version"), std::string::npos) << what;
  }
}

}  // namespace
}  // namespace robotperf::plugin
