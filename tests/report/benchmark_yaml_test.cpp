#include "robotperf/report/benchmark_yaml.hpp"

#include <gtest/gtest.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <tuple>

#include "../shared_data.hpp"
#include "sample_runs.hpp"

namespace robotperf::report {
namespace {

namespace fs = std::filesystem;

// The published RobotPerf results, and a1's among them.
fs::path published() {
  return shared_data("robotperf");
}
fs::path published_a1() {
  return shared_data("robotperf/perception/a1_perception_2nodes/benchmark.yaml");
}

std::string read_text(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}

bool has_flag(const PublishedResult& r, const std::string& part) {
  for (const auto& f : r.flags) {
    if (f.find(part) != std::string::npos) return true;
  }
  return false;
}

class BenchmarkYaml : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("robotperf-byaml-" + std::to_string(getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // Exported entries of a synthetic run with power.
  std::vector<PublishedResult> sample_entries() {
    testing::SampleRun s;
    s.gpu = "NVIDIA GeForce RTX 3060";
    const auto run = load_run(testing::write_sample(dir_, s, false, 42.5));
    return export_entries(run, {});
  }

  fs::path dir_;
};

TEST_F(BenchmarkYaml, ImportsEveryPublishedA1ResultAndFlagsTheDefectiveRows) {
  const auto b = import_benchmark_yaml(published_a1());
  const std::string text = read_text(published_a1());
  std::size_t entries_in_text = 0;
  for (std::size_t at = 0; (at = text.find("\n- result:", at)) != std::string::npos; ++at)
    ++entries_in_text;
  EXPECT_EQ(b.id, "a1");
  EXPECT_EQ(b.category, "perception");
  ASSERT_EQ(b.results.size(), entries_in_text);
  EXPECT_GT(b.results.size(), 300u);

  std::size_t negative = 0, over_100 = 0, zero_power = 0, tiny_power = 0;
  for (const auto& r : b.results) {
    EXPECT_FALSE(r.hardware.empty()) << "line " << r.line;
    EXPECT_TRUE(std::isfinite(r.value)) << "line " << r.line;
    EXPECT_GT(r.line, 0);
    // The entry's line holds "- result:".
    if (r.note.find("min_latency -") != std::string::npos ||
        r.note.find("min_benchmark -") != std::string::npos) {
      ++negative;
      EXPECT_TRUE(has_flag(r, "negative min latency")) << r.note;
    }
    if (r.note.find("-2298.236986") != std::string::npos) {
      EXPECT_EQ(r.note_min, -2298.236986);
    }
    if (r.metric == "power" && r.value > 0 && r.value < 1e-40) {
      ++tiny_power;
      EXPECT_TRUE(has_flag(r, "below 1 mW")) << "line " << r.line;
    }
    if (r.note_loss_percent && *r.note_loss_percent > 100) {
      ++over_100;
      EXPECT_TRUE(has_flag(r, "above 100 %")) << "line " << r.line;
    }
    if (r.metric == "power" && r.value == 0.0) {
      ++zero_power;
      EXPECT_TRUE(has_flag(r, "W <= 0")) << "line " << r.line;
    }
    // A row whose note says nothing wrong and whose value is sane has no flag.
    if (r.metric == "latency" && r.value > 0 && r.note_min.value_or(1) > 0 &&
        r.note_loss_percent.value_or(0) <= 100) {
      EXPECT_TRUE(r.flags.empty()) << "line " << r.line << ": " << r.flags.front();
    }
  }
  EXPECT_EQ(negative, 2u);
  EXPECT_GE(over_100, 20u);
  EXPECT_EQ(zero_power, 13u);
  EXPECT_EQ(tiny_power, 1u);  // 8.97e-44 W
  EXPECT_EQ(b.flagged(), negative + over_100 + zero_power + tiny_power);

  // The first published row: Intel i7-12700H, 20.4 ms, with its note figures.
  const auto& first = b.results.front();
  EXPECT_EQ(first.hardware, "Intel i7-12700H");
  EXPECT_EQ(first.metric, "latency");
  EXPECT_EQ(first.value, 20.4);
  EXPECT_EQ(first.note_mean, 14.73);
  EXPECT_EQ(first.note_rms, 14.84);
  EXPECT_EQ(first.category, "workstation");
  EXPECT_EQ(first.timestampt, "07-07-2023");
  // The reported line is the entry's "- result:" line.
  std::istringstream lines(text);
  std::string line;
  for (int n = 1; std::getline(lines, line); ++n) {
    if (n == first.line) {
      EXPECT_EQ(line, "- result:");
    }
  }

  const std::string report = flagged_rows_report(b);
  EXPECT_NE(report.find("benchmark.yaml:"), std::string::npos);
  EXPECT_NE(report.find("NVIDIA Jetson Nano · latency 1120.322889 ms: negative min latency"),
            std::string::npos)
      << report;
}

TEST_F(BenchmarkYaml, ImportsEveryPublishedFile) {
  std::size_t files = 0;
  for (const auto& e : fs::recursive_directory_iterator(published())) {
    if (e.path().filename() != "benchmark.yaml") continue;
    ++files;
    EXPECT_NO_THROW(import_benchmark_yaml(e.path())) << e.path();
  }
  EXPECT_GT(files, 30u);
}

// RobotPerf's VPN ping-pongs (n5 to n8): their rows import with both hosts named and the median.
TEST_F(BenchmarkYaml, ImportsThePublishedVpnRows) {
  for (const auto& [package, rows, first_value] :
       std::vector<std::tuple<std::string, std::size_t, double>>{
           {"n5_intra_network_vpn", 2, 0.4974},
           {"n6_intra_network_security_vpn", 2, 0.5641},
           {"n7_inter_network_vpn", 1, 28.0395},
           {"n8_inter_network_vpn_security", 1, 29.4749}}) {
    const auto b = import_benchmark_yaml(published() / "middleware" / package / "benchmark.yaml");
    EXPECT_EQ(b.name, package);
    ASSERT_EQ(b.results.size(), rows) << package;
    EXPECT_DOUBLE_EQ(b.results[0].value, first_value) << package;
    EXPECT_NE(b.results[0].hardware.find(" <-> "), std::string::npos) << b.results[0].hardware;
    EXPECT_EQ(b.results[0].type, "grey");
  }
}

TEST_F(BenchmarkYaml, PowerBelowOneMilliwattIsFlagged) {
  PublishedResult r;
  r.metric = "power";
  r.metric_unit = "W";
  r.value = 8.97e-44;
  r.value_text = "8.97e-44";
  check_published(r);
  ASSERT_EQ(r.flags.size(), 1u);
  EXPECT_NE(r.flags[0].find("below 1 mW"), std::string::npos);
  r.value = 5.8;
  check_published(r);
  EXPECT_TRUE(r.flags.empty());
  r.metric = "latency";
  r.value = -3;
  check_published(r);
  EXPECT_TRUE(has_flag(r, "negative latency"));
}

// a1's file writes one platform both as "...(ROBOTCORE\xAE Perception)" in double quotes (YAML
// reads ®) and as a plain scalar (YAML keeps the four characters): both are the one platform.
TEST_F(BenchmarkYaml, HardwareNamesLoseTheirEscapes) {
  const auto b = import_benchmark_yaml(published_a1());
  std::size_t robotcore_12700h = 0;
  for (const auto& r : b.results) {
    EXPECT_EQ(r.hardware.find("\\x"), std::string::npos) << "line " << r.line << ": " << r.hardware;
    robotcore_12700h +=
        r.hardware == "Intel i7-12700H + NVIDIA GeForce RTX 3060 (ROBOTCORE\xC2\xAE Perception)";
  }
  EXPECT_EQ(robotcore_12700h, 10u);
}

// RobotPerf's notes state the input rate in several ways; a sweep is not a rate, and a measured
// figure ("mean_benchmark 10.00 fps", "Mean FPS observed 174") states none.
TEST_F(BenchmarkYaml, NotesStateTheirRate) {
  const std::pair<const char*, const char*> cases[] = {
      {"lost 0.00 %, throughput bounded to 30fps", "30 Hz"},
      {"Fixed at 30 FPS. lost 0.00 %.", "30 Hz"},
      {"mean 0.08 ms, rms 0.10 ms, max 0.55 ms, min 0.02 ms, lost 0.00%, update rate 10 Hz",
       "10 Hz"},
      {"mean 5.51 ms, lost 0.00 %, throughput swept from 30 to 300 fps", "30-300 Hz sweep"},
      {"lost messages 0.00 %, throughput swept 30-300fps", "30-300 Hz sweep"},
      {"Throughput configured in the 30-500 FPS range. Mean FPS observed 174.432.",
       "30-500 Hz sweep"},
      {"mean_benchmark 10.00 fps, rms_benchmark 10.00 fps, lost messages 0.00 %", ""},
      {"Mean FPS observed 220.91.", ""},
      {"", ""}};
  for (const auto& [note, rate] : cases) {
    PublishedResult r;
    r.metric = "latency";
    r.value = 5;
    r.note = note;
    check_published(r);
    EXPECT_EQ(r.stated_rate(), rate) << note;
  }
}

// Found by fuzz_benchmark_packages: a figure in a note beyond double's range threw stod's
// out_of_range out of import.
TEST_F(BenchmarkYaml, NoteFiguresBeyondDoubleAreFlaggedNotThrown) {
  PublishedResult r;
  r.metric = "latency";
  r.value = 5;
  r.value_text = "5";
  const std::string huge = "1" + std::string(400, '0');
  r.note = "mean 1e999 ms, max 7 ms, lost " + huge + " %";
  EXPECT_NO_THROW(check_published(r));
  EXPECT_TRUE(has_flag(r, "the note's mean (1e999) is not a number"));
  EXPECT_TRUE(has_flag(r, "the note's loss (" + huge + " %) is not a number"));
  EXPECT_EQ(r.note_max, 7.0);
  EXPECT_FALSE(r.note_mean.has_value());
}

TEST_F(BenchmarkYaml, ExportGivesRobotPerfEntries) {
  const auto entries = sample_entries();
  ASSERT_EQ(entries.size(), 3u);
  EXPECT_EQ(entries[0].metric, "latency");
  EXPECT_EQ(entries[0].metric_unit, "ms");
  EXPECT_EQ(entries[0].type, "black");
  EXPECT_EQ(entries[0].hardware, "AMD Ryzen 7 5800X + NVIDIA GeForce RTX 3060");
  EXPECT_EQ(entries[0].category, "workstation");
  EXPECT_EQ(entries[0].datasource, "perception/image");
  EXPECT_EQ(entries[0].timestampt, "2026-09-21 14:13:20");
  EXPECT_NE(entries[0].note.find("mean "), std::string::npos);
  EXPECT_NE(entries[0].note.find("lost 0.00 %"), std::string::npos);
  EXPECT_EQ(entries[1].metric, "throughput");
  EXPECT_EQ(entries[1].metric_unit, "fps");
  EXPECT_EQ(entries[1].value, 30.0);
  EXPECT_EQ(entries[2].metric, "power");
  EXPECT_EQ(entries[2].value, 42.5);
  for (auto e : entries) {
    check_published(e);
    EXPECT_TRUE(e.flags.empty()) << e.flags.front();
  }
}

// A run's outputs (graph.yaml `outputs:`) read from its file: the first's jitter goes into the
// latency row's note, and each further output gets a latency row of its own, naming it. The
// jitter's figures come after the latency's, so a re-imported row reads the latency's.
TEST_F(BenchmarkYaml, ExportedRowsCarryEachOutputAndItsJitter) {
  const fs::path file = testing::write_sample(dir_, {});
  nlohmann::json j = nlohmann::json::parse(read_text(file));
  auto output = [](const std::string& topic, double loss, double max_ms) {
    return nlohmann::json{
        {"topic", topic},
        {"matched", 30},
        {"lost", 10},
        {"loss_percent", loss},
        {"latency_ms",
         {{"from_scheduled", {{"count", 30}, {"mean", 6.5}, {"p50", 6.1}, {"max", max_ms}}}}},
        {"throughput_hz", 25.0},
        {"period_ms", 33.333},
        {"interval_ms", {{"count", 29}, {"p50", 33.4}}},
        {"jitter_ms", {{"count", 29}, {"mean", 0.25}, {"p99", 1.5}, {"max", 33.0}}}};
  };
  j["outputs"] = {output("/image_rect", 0.0, 7.0), output("/slow", 25.0, 9.5)};
  std::ofstream(file) << j.dump();
  const StoredRun run = load_run(file);
  ASSERT_EQ(run.outputs.size(), 2u);
  EXPECT_EQ(run.outputs[1].topic, "/slow");
  EXPECT_DOUBLE_EQ(run.outputs[1].jitter.p99, 1.5);
  EXPECT_DOUBLE_EQ(run.outputs[1].period_ms, 33.333);
  auto entries = export_entries(run, {});
  ASSERT_EQ(entries.size(), 3u);  // latency, /slow's latency, throughput
  EXPECT_NE(entries[0].note.find("output jitter |interval - period| mean 0.250 ms, p99 1.500 ms"),
            std::string::npos)
      << entries[0].note;
  EXPECT_EQ(entries[1].metric, "latency");
  EXPECT_EQ(entries[1].value, 9.5);
  EXPECT_TRUE(entries[1].note.starts_with("output /slow: mean 6.500 ms")) << entries[1].note;
  EXPECT_NE(entries[1].note.find("lost 25.00 %"), std::string::npos) << entries[1].note;
  for (auto& e : entries) check_published(e);
  EXPECT_DOUBLE_EQ(*entries[1].note_mean, 6.5);
  EXPECT_DOUBLE_EQ(*entries[1].note_loss_percent, 25.0);
}

// An exported row states its input rate as imported rows are read (so a re-imported row is
// matched on its rate), and its throughput says whether it is offered-bounded or a peak.
TEST_F(BenchmarkYaml, ExportedNotesReadBackTheirRateAndSayWhichThroughputItIs) {
  StoredRun run = load_run(testing::write_sample(dir_, {}));
  run.rate_hz = 200;
  auto entries = export_entries(run, {});
  ASSERT_EQ(entries.size(), 2u);
  for (auto& e : entries) {
    check_published(e);
    ASSERT_TRUE(e.note_rate_hz) << e.note;
    EXPECT_EQ(e.note_rate_hz->first, 200.0) << e.note;
    EXPECT_EQ(e.note_rate_hz->second, 200.0) << e.note;
  }
  EXPECT_NE(entries[1].note.find("offered-bounded"), std::string::npos) << entries[1].note;

  run.throughput_kind = "peak";
  entries = export_entries(run, {});
  ASSERT_EQ(entries.size(), 2u);
  EXPECT_EQ(entries[1].metric, "throughput");
  EXPECT_NE(entries[1].note.find("peak"), std::string::npos) << entries[1].note;
  EXPECT_EQ(entries[1].note.find("offered-bounded"), std::string::npos) << entries[1].note;
  check_published(entries[1]);
  EXPECT_FALSE(entries[1].note_rate_hz) << "a peak search was fed no one rate";
}

// export -> merge -> import preserves every field, and merging leaves every existing byte.
void expect_round_trip(const std::string& original, const std::vector<PublishedResult>& entries,
                       const fs::path& file, std::size_t dash_col) {
  const auto merged = merge_entries(original, file.string(), entries);
  EXPECT_EQ(merged.added, entries.size());
  // The original is the merged text minus one inserted block.
  std::size_t prefix = 0;
  while (prefix < original.size() && original[prefix] == merged.text[prefix]) ++prefix;
  const std::size_t suffix = original.size() - prefix;
  ASSERT_GT(merged.text.size(), original.size());
  EXPECT_EQ(merged.text.substr(merged.text.size() - suffix), original.substr(prefix))
      << "existing content changed";
  const std::string inserted = merged.text.substr(prefix, merged.text.size() - original.size());
  EXPECT_EQ(inserted.find_first_not_of(' '), dash_col) << inserted;

  files::write_file_atomically(file, merged.text);
  const auto back = import_benchmark_yaml(file);
  ASSERT_GE(back.results.size(), entries.size());
  const std::size_t first_new = back.results.size() - entries.size();
  for (std::size_t i = 0; i < entries.size(); ++i) {
    const auto& got = back.results[first_new + i];
    EXPECT_TRUE(got.same_entry(entries[i])) << i;
    EXPECT_EQ(got.type, entries[i].type);
    EXPECT_EQ(got.metric, entries[i].metric);
    EXPECT_EQ(got.metric_unit, entries[i].metric_unit);
    EXPECT_EQ(got.hardware, entries[i].hardware);
    EXPECT_EQ(got.category, entries[i].category);
    EXPECT_EQ(got.timestampt, entries[i].timestampt);
    EXPECT_EQ(got.value, entries[i].value);  // exactly
    EXPECT_EQ(got.note, entries[i].note);
    EXPECT_EQ(got.datasource, entries[i].datasource);
    EXPECT_TRUE(got.flags.empty());
  }
  // Merging again adds nothing.
  const auto again = merge_entries(merged.text, file.string(), entries);
  EXPECT_EQ(again.added, 0u);
  EXPECT_EQ(again.already_present, entries.size());
  EXPECT_EQ(again.text, merged.text);
}

TEST_F(BenchmarkYaml, RoundTripIntoThePublishedA1File) {
  const std::string original = read_text(published_a1());
  const auto before = import_benchmark_yaml(published_a1());
  const auto entries = sample_entries();
  const fs::path file = dir_ / "a1" / "benchmark.yaml";
  expect_round_trip(original, entries, file, 0);
  const auto after = import_benchmark_yaml(file);
  ASSERT_EQ(after.results.size(), before.results.size() + entries.size());
  for (std::size_t i = 0; i < before.results.size(); ++i) {
    EXPECT_TRUE(after.results[i].same_entry(before.results[i])) << i;
    EXPECT_EQ(after.results[i].line, before.results[i].line);
  }
  EXPECT_EQ(after.short_description, before.short_description);  // the key after results
}

TEST_F(BenchmarkYaml, RoundTripIntoAnEmptyPackageFile) {
  const std::string original = read_text(fs::path(ROBOTPERF_SOURCE_DIR) /
                                         "benchmarks/perception/a1_perception_2nodes/"
                                         "benchmark.yaml");
  ASSERT_NE(original.find("results: []"), std::string::npos);
  const auto entries = sample_entries();
  const auto merged = merge_entries(original, "benchmark.yaml", entries);
  EXPECT_EQ(merged.added, 3u);
  EXPECT_EQ(merged.text.substr(0, original.find("results: []")),
            original.substr(0, original.find("results: []")));
  const fs::path file = dir_ / "benchmark.yaml";
  files::write_file_atomically(file, merged.text);
  const auto back = import_benchmark_yaml(file);
  ASSERT_EQ(back.results.size(), 3u);
  for (std::size_t i = 0; i < 3; ++i) EXPECT_TRUE(back.results[i].same_entry(entries[i]));
  // And from there, a second run appends after the first.
  auto second = entries[0];
  second.timestampt = "2026-09-22 10:00:00";
  expect_round_trip(merged.text, {second}, file, 0);
}

TEST_F(BenchmarkYaml, RoundTripKeepsTheTemplatesIndentation) {
  const std::string original = read_text(published() / "TEMPLATE.yaml");
  auto entries = sample_entries();
  entries[0].hardware = "Hardware with \"quotes\": and a colon";
  entries[0].note = "line one\nline two, 100 % \\ backslash, ROBOTCORE\xC2\xAE";
  expect_round_trip(original, entries, dir_ / "benchmark.yaml", 2);
}

TEST_F(BenchmarkYaml, RefusesWhatItCannotMergeSafely) {
  const auto entries = sample_entries();
  EXPECT_THROW(merge_entries("id: a1\nresults: [{result: {metric: latency}}]\n", "f.yaml", entries),
               ReportError);
  try {
    merge_entries("id: a1\nresults: [\n", "f.yaml", entries);
    FAIL() << "malformed YAML merged";
  } catch (const ReportError& e) {
    EXPECT_NE(std::string(e.what()).find("f.yaml:"), std::string::npos) << e.what();
  }
  const auto fresh = merge_entries("id: x1\nname: x1_new\n", "f.yaml", entries);
  EXPECT_EQ(fresh.added, 3u);
  EXPECT_EQ(fresh.text.substr(0, 20), "id: x1\nname: x1_new\n");
}

TEST_F(BenchmarkYaml, NumbersReadBackExactly) {
  for (double v : {0.0, 20.4, 46.155170000000005, 8.97e-44, 1e300, 30.0, -2298.236986}) {
    EXPECT_EQ(YAML::Load("k: " + shortest_number(v))["k"].as<double>(), v);
  }
}

TEST_F(BenchmarkYaml, ImportedFilesRoundTripAsJson) {
  const auto b = import_benchmark_yaml(published_a1());
  const auto back = published_from_json(to_json(b), "x.json");
  ASSERT_EQ(back.results.size(), b.results.size());
  for (std::size_t i = 0; i < b.results.size(); ++i) {
    EXPECT_TRUE(back.results[i].same_entry(b.results[i]));
    EXPECT_EQ(back.results[i].flags, b.results[i].flags);
    EXPECT_EQ(back.results[i].line, b.results[i].line);
  }
  EXPECT_THROW(published_from_json({{"schema", "other"}}, "x.json"), ReportError);
}

TEST_F(BenchmarkYaml, BadFilesGiveOneLine) {
  std::ofstream(dir_ / "bad.yaml") << "id: a1\nresults:\n  - result: {metric: [\n";
  try {
    import_benchmark_yaml(dir_ / "bad.yaml");
    FAIL();
  } catch (const ReportError& e) {
    EXPECT_NE(std::string(e.what()).find("bad.yaml:"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("malformed YAML"), std::string::npos);
  }
  std::ofstream(dir_ / "list.yaml") << "- 1\n- 2\n";
  EXPECT_THROW(import_benchmark_yaml(dir_ / "list.yaml"), ReportError);
  EXPECT_THROW(import_benchmark_yaml(dir_ / "missing.yaml"), ReportError);
}

// A package's category is the folder it lies in, as the harness records a loaded package's; the
// id's letter says it only for a published RobotPerf file, which may be a copy anywhere.
TEST_F(BenchmarkYaml, TheCategoryComesFromThePackageFolder) {
  const auto write = [&](const fs::path& package, const std::string& id, bool graph) {
    fs::create_directories(package);
    std::ofstream(package / "benchmark.yaml") << "id: " << id << "\nname: " << id << "_x\n";
    if (graph) std::ofstream(package / "graph.yaml") << "nodes: []\n";
    return package / "benchmark.yaml";
  };
  // robotperf's package of a plug-in's category, whatever its id's letter.
  EXPECT_EQ(import_benchmark_yaml(write(dir_ / "mine" / "a7_x", "a7", true)).category, "mine");
  // A copy of a published RobotPerf file: its format's category for the id.
  EXPECT_EQ(import_benchmark_yaml(write(dir_ / "copies" / "a5", "a5", false)).category,
            "perception");
  // A published file of an id RobotPerf does not number: the folder.
  EXPECT_EQ(import_benchmark_yaml(write(dir_ / "theirs" / "z1_x", "z1", false)).category, "theirs");
  // The caller's, when it knows it.
  EXPECT_EQ(import_benchmark_yaml(dir_ / "copies" / "a5" / "benchmark.yaml", "given").category,
            "given");
}

}  // namespace
}  // namespace robotperf::report
