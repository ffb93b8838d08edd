// Plug-ins and benchmark folders from the command line, as a user gives them.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "../command_line.hpp"
#include "robotperf/rmw/transport.hpp"

namespace {

namespace fs = std::filesystem;

using robotperf::test_support::Outcome;
using robotperf::test_support::robotperf_cli;

Outcome run(const std::string& command) {
  return robotperf::test_support::shell(command);
}

std::size_t lines(const std::string& s) {
  return std::ranges::count(s, '\n');
}

class PluginCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("robotperf-plugin-cli-" + std::to_string(getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // A benchmark folder with one package, x1, running the test plug-in's kernel.
  fs::path benchmark_folder() {
    const fs::path package = dir_ / "benchmarks" / "mine" / "x1_scale";
    fs::create_directories(package);
    std::ofstream(package / "benchmark.yaml")
        << "id: x1\nname: x1_scale\nshort: the test plug-in's kernel\ndescription: test\n"
           "results: []\nfunctional:\n  thresholds:\n    match_fraction: {min: 1.0}\n";
    std::ofstream(package / "graph.yaml")
        << "dataset: test_plugin/joints\nrate_hz: 20\nwarmup: 2\n"
           "validity: {min_samples: 10, max_loss_percent: 0.0}\n"
           "inputs:\n  - {topic: /states, type: sensor_msgs/msg/JointState, stream: states}\n"
           "output: {topic: /scaled, type: sensor_msgs/msg/JointState}\n"
           "nodes:\n  - name: scale\n    kernel: test_plugin/scale\n"
           "    topics: {input: /states, output: /scaled}\n"
           "functional:\n  evaluator: test_plugin/scaled\n  truth: {scaled: scaled}\n";
    return dir_ / "benchmarks";
  }
  std::string domain() const { return std::to_string(robotperf::rmw::reserved_domain()); }

  fs::path dir_;
};

TEST_F(PluginCli, ListsWhatAPluginRegistersAndWhereItCameFrom) {
  const auto o = robotperf_cli(std::string("--plugin ") + GOOD_PLUGIN + " list kernels");
  ASSERT_EQ(o.exit_code, 0) << o.out;
  EXPECT_NE(o.out.find("test_plugin/scale  (from " + fs::canonical(GOOD_PLUGIN).string() +
                       "; backends: cpu, test_backend)"),
            std::string::npos)
      << o.out;
  EXPECT_NE(o.out.find("factor (double, default 2): scale factor"), std::string::npos);
  EXPECT_NE(o.out.find("image_proc/rectify  (from built-in perception"), std::string::npos);
  const auto d = robotperf_cli(std::string("list datasets --plugin ") + GOOD_PLUGIN);
  EXPECT_NE(d.out.find("test_plugin/joints"), std::string::npos) << d.out;
  EXPECT_NE(d.out.find("[truth] scaled inputs"), std::string::npos) << d.out;
  const auto e = robotperf_cli(std::string("list evaluators --plugin ") + GOOD_PLUGIN);
  EXPECT_NE(e.out.find("test_plugin/scaled"), std::string::npos) << e.out;
  EXPECT_NE(e.out.find("tolerance (double, default 1e-12)"), std::string::npos) << e.out;
}

TEST_F(PluginCli, PluginPathLoadsFilesAndFolders) {
  fs::create_directories(dir_ / "plugins");
  fs::copy_file(GOOD_PLUGIN, dir_ / "plugins" / "libgood.so");
  const auto o =
      run("ROBOTPERF_PLUGIN_PATH=/nonexistent-is-an-error:" + (dir_ / "plugins").string() + " " +
          ROBOTPERF_EXECUTABLE + " list kernels");
  EXPECT_EQ(o.exit_code, 2) << o.out;
  EXPECT_EQ(o.out, "robotperf: plug-in /nonexistent-is-an-error: file not found\n");
  const auto ok = run("ROBOTPERF_PLUGIN_PATH=" + (dir_ / "plugins").string() + " " +
                      ROBOTPERF_EXECUTABLE + " list kernels");
  ASSERT_EQ(ok.exit_code, 0) << ok.out;
  EXPECT_NE(ok.out.find("test_plugin/scale  (from " + (dir_ / "plugins" / "libgood.so").string()),
            std::string::npos)
      << ok.out;
}

TEST_F(PluginCli, EachLoadingErrorIsOneLineAndExitCode2) {
  const fs::path text = dir_ / "notes.txt";
  std::ofstream(text) << "hello\n";
  const std::pair<std::string, std::string> cases[] = {
      {text.string(), "cannot be loaded as a shared library"},
      {NOT_A_PLUGIN, "not a robotperf plug-in"},
      {VERSION_MISMATCH_PLUGIN, "built against plug-in API version"},
      {DUPLICATE_PLUGIN, "kernel 'util/relay' is already registered by built-in util"},
      {THROWING_PLUGIN, "registration failed: no licence for this accelerator"},
  };
  for (const auto& [file, problem] : cases) {
    const auto o = robotperf_cli("--plugin " + file + " list kernels");
    EXPECT_EQ(o.exit_code, 2) << file << ": " << o.out;
    EXPECT_EQ(lines(o.out), 1u) << o.out;
    EXPECT_NE(o.out.find("robotperf: plug-in " + fs::weakly_canonical(file).string() + ": "),
              std::string::npos)
        << o.out;
    EXPECT_NE(o.out.find(problem), std::string::npos) << o.out;
  }
}

TEST_F(PluginCli, BenchmarkFoldersAddToTheBuiltInOnes) {
  const fs::path folder = benchmark_folder();
  const auto o = robotperf_cli("--plugin " + std::string(GOOD_PLUGIN) + " --benchmarks " +
                               folder.string() + " list");
  ASSERT_EQ(o.exit_code, 0) << o.out;
  EXPECT_NE(o.out.find("a1  "), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("x1  x1_scale"), std::string::npos) << o.out;
  // Without the plug-in the package cannot be loaded, and says why.
  const auto missing = robotperf_cli("--benchmarks " + folder.string() + " describe x1");
  EXPECT_EQ(missing.exit_code, 2) << missing.out;
  EXPECT_NE(missing.out.find("unknown kernel 'test_plugin/scale'"), std::string::npos)
      << missing.out;
  const auto described =
      robotperf_cli("--benchmarks " + folder.string() + " describe x1 --plugin " + GOOD_PLUGIN);
  EXPECT_EQ(described.exit_code, 0) << described.out;
  EXPECT_NE(described.out.find("param factor = 2 (default)"), std::string::npos) << described.out;
}

TEST_F(PluginCli, ADuplicateIdNamesBothPackages) {
  const fs::path copy = dir_ / "benchmarks" / "perception" / "a5_resize";
  fs::create_directories(copy.parent_path());
  fs::copy(fs::path(ROBOTPERF_SOURCE_DIR) / "benchmarks/perception/a5_resize", copy);
  const auto o = robotperf_cli("--benchmarks " + (dir_ / "benchmarks").string() + " run a5");
  EXPECT_EQ(o.exit_code, 2) << o.out;
  EXPECT_EQ(lines(o.out), 1u) << o.out;
  EXPECT_NE(o.out.find("benchmark id a5 is defined twice"), std::string::npos) << o.out;
  EXPECT_NE(o.out.find(copy.string()), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("benchmarks/perception/a5_resize and"), std::string::npos) << o.out;
}

TEST_F(PluginCli, PerNodeChildrenLoadThePlugin) {
  const fs::path folder = benchmark_folder();
  const auto o =
      robotperf_cli("--plugin " + std::string(GOOD_PLUGIN) + " --benchmarks " + folder.string() +
                    " run x1 --rmw fastdds --processes per-node --count 30" + " --quiet --domain " +
                    domain() + " --output " + (dir_ / "out").string());
  ASSERT_EQ(o.exit_code, 0) << o.out;
  std::vector<fs::path> results;
  for (const auto& e : fs::directory_iterator(dir_ / "out"))
    if (e.path().extension() == ".json") results.push_back(e.path());
  ASSERT_EQ(results.size(), 1u);
  std::ifstream in(results[0]);
  const auto j = nlohmann::json::parse(in);
  EXPECT_EQ(j["counts"]["matched"], 28);
  EXPECT_EQ(j["functional"]["valid"], true) << j["functional"].dump();
  EXPECT_GT(j["nodes"][0]["pid"].get<int>(), 0);
}

}  // namespace
