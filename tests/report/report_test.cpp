#include "robotperf/report/report.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>

#include "../shared_data.hpp"
#include "report_model.hpp"
#include "robotperf/metrics/latency_stats.hpp"
#include "robotperf/report/histogram.hpp"
#include "robotperf/report/readme.hpp"
#include "robotperf/report/run_store.hpp"
#include "robotperf/report/significance.hpp"
#include "robotperf/report/standing.hpp"
#include "sample_runs.hpp"

namespace robotperf::report {
namespace {

namespace fs = std::filesystem;

fs::path published_a1() {
  return shared_data("robotperf/perception/a1_perception_2nodes/benchmark.yaml");
}

std::size_t count(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (std::size_t at = 0; (at = text.find(what, at)) != std::string::npos; at += what.size()) ++n;
  return n;
}

std::string read_text(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}

class Report : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("robotperf-report-" + std::to_string(getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // Two runs on each of two machines, one with a CSV, all with power.
  void write_two_machines(double base_b_1, double base_b_2) {
    int64_t t = 1'790'000'000'000'000'000;
    auto sample = [&](const std::string& cpu, double base) {
      testing::SampleRun s;
      s.cpu = cpu;
      s.base_latency_ms = base;
      s.start_unix_ns = (t += 60'000'000'000);
      return s;
    };
    testing::write_sample(dir_, sample("AMD Ryzen 7 5800X 8-Core Processor", 5.0), true, 40);
    testing::write_sample(dir_, sample("AMD Ryzen 7 5800X 8-Core Processor", 5.1), false, 41);
    testing::write_sample(dir_, sample("Intel(R) Core(TM) i7-12700H CPU @ 2.30GHz", base_b_1),
                          false, 30);
    testing::write_sample(dir_, sample("Intel(R) Core(TM) i7-12700H CPU @ 2.30GHz", base_b_2),
                          false, 31);
  }

  fs::path dir_;
};

TEST(Significance, WelchMatchesKnownValues) {
  const std::vector<double> a = {1, 2, 3, 4, 5}, b = {2, 4, 6, 8, 10};
  const auto w = welch_test(a, b);
  EXPECT_NEAR(w.t, -1.8974, 1e-4);
  EXPECT_NEAR(w.degrees_of_freedom, 5.8824, 1e-4);
  EXPECT_NEAR(w.p_value, 0.1077, 1e-3);  // R: t.test(1:5, c(2,4,6,8,10))
  EXPECT_NEAR(regularized_incomplete_beta(0.5, 2, 3), 0.6875, 1e-12);
  EXPECT_NEAR(student_t_two_sided_p(2.0, 10), 0.07339, 1e-4);
  EXPECT_NEAR(student_t_two_sided_p(0.0, 3), 1.0, 1e-12);
  EXPECT_EQ(welch_test(4, 0, 3, 4, 0, 3).p_value, 1.0);
  EXPECT_EQ(welch_test(4, 0, 3, 5, 0, 3).p_value, 0.0);
  EXPECT_THROW(welch_test(std::vector<double>{1}, b), std::invalid_argument);
}

// results list: every column as wide as its widest cell (a per-node transport, a long hardware
// name), and a long INVALID reason whole, on its own line.
TEST(RunsTable, ColumnsFitTheirWidestCellAndLongReasonsStayWhole) {
  std::vector<StoredRun> runs(3);
  runs[0].path = "results/a1-intra-20261126T142921174Z.json";
  runs[0].rmw = "intra";
  runs[0].hardware = "AMD EPYC";
  runs[0].valid = true;
  runs[1].path = "results/a1-cyclonedds-20261126T142942891Z.json";
  runs[1].rmw = "cyclonedds";
  runs[1].processes = "per-node";
  runs[1].hardware = "Intel(R) Xeon(R) Platinum 8480+ + NVIDIA H100 80GB HBM3";
  runs[1].valid = true;
  runs[2].path = "results/a1-fastdds-20261126T143000000Z.json";
  runs[2].rmw = "fastdds";
  runs[2].hardware = "AMD EPYC";
  runs[2].invalid_reasons = {std::string(600, 'x')};
  for (auto& r : runs) {
    r.benchmark_id = "a1";
    r.type = "black";
    r.started_utc = "2026-11-26T14:29:21Z";
    r.latency.max = 4.77;
    r.latency.p50 = 3.08;
    r.throughput_hz = 30.02;
  }
  const std::string table = runs_table(runs);
  std::vector<std::string> lines;
  std::istringstream in(table);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  ASSERT_EQ(lines.size(), 4u) << table;
  const std::size_t date = lines[0].find("date (UTC)");
  const std::size_t validity = lines[0].find("validity");
  for (std::size_t i = 1; i < lines.size(); ++i) {
    EXPECT_EQ(lines[i].find("2026-11-26 14:29:21"), date) << table;
    EXPECT_EQ(lines[i].find(i == 3 ? "INVALID" : "valid"), validity) << table;
  }
  EXPECT_NE(lines[2].find("cyclonedds/per-node"), std::string::npos) << table;
  EXPECT_NE(lines[2].find(runs[1].hardware), std::string::npos) << table;
  EXPECT_TRUE(lines[3].ends_with("INVALID: " + std::string(600, 'x'))) << table;
}

TEST(Histogram, CountsEverySampleAndReadsBack) {
  const std::vector<double> samples = {1.0, 1.05, 10.0, 0.0, -1.0, 3.3};
  const auto h = make_log_histogram(samples, 10);
  EXPECT_EQ(h.total(), samples.size());
  EXPECT_EQ(h.nonpositive, 2u);
  EXPECT_LE(h.lower_edge(0), 1.0);
  EXPECT_GT(h.upper_edge(h.counts.size() - 1), 10.0);
  EXPECT_EQ(h.counts.front(), 2u);  // 1.0 and 1.05 share the bin [1, 1.26)
  const auto back = log_histogram_from_json(to_json(h));
  ASSERT_TRUE(back);
  EXPECT_EQ(back->counts, h.counts);
  EXPECT_EQ(back->first_index, h.first_index);
  EXPECT_FALSE(log_histogram_from_json(nlohmann::json()));  // older files have none
  EXPECT_THROW(log_histogram_from_json(nlohmann::json::object()), nlohmann::json::exception);
  EXPECT_THROW(make_log_histogram(samples, 0), std::invalid_argument);
}

// Bins whose edges are beyond double's range would put infinities on the report's axis: such a
// histogram is refused where it is read.
TEST(Histogram, EdgesBeyondDoublesRangeAreRefused) {
  for (const int first_index : {20000, -20000}) {
    const nlohmann::json j = {{"scale", "log10"},
                              {"bins_per_decade", 1},
                              {"first_index", first_index},
                              {"counts", {1, 2}}};
    try {
      log_histogram_from_json(j);
      ADD_FAILURE() << "first_index " << first_index << " was read";
    } catch (const ReportError& e) {
      EXPECT_NE(std::string(e.what()).find("beyond the range of a double"), std::string::npos)
          << e.what();
    }
  }
}

// An axis up to the end of double's range still has a handful of ticks, found in bounded time.
TEST(Distribution, AnAxisNearDoublesLimitIsDrawnInBoundedTime) {
  detail::Distribution d;
  d.label = "huge";
  d.source = "stored percentiles";
  d.points = {{1.0, 0.5}, {1.7e308, 1.0}};
  d.p50 = 1.0;
  d.p99 = 1.7e308;
  const std::string svg = detail::distribution_svg({d}, "a1");
  EXPECT_LE(count(svg, "<line x1="), 20u);
  EXPECT_EQ(svg.find("inf"), std::string::npos) << svg;
  EXPECT_EQ(svg.find("nan"), std::string::npos);
}

// Each radar axis is logarithmic only when its own values span more than 20x: a 10 % difference
// on another axis stays a 10 % difference, near the rim, not stretched from 0.1 to 1 of it.
TEST(Radar, EachAxisChoosesItsOwnScale) {
  detail::Radar r;
  r.category = "perception";
  r.metric = "latency";
  r.unit = "ms";
  r.axes = {"a1", "a2", "a3"};
  r.series = {"X", "Y"};
  r.series_local = {true, true};
  r.colours = {0, 1};
  r.values = {{10, 1, 100}, {11, 100, 105}};
  const std::string svg = detail::radar_svg(r);
  // The centre is (240, 200), the radius 120; a1 points straight up.
  const std::regex circle("<circle cx=\"([0-9.]+)\" cy=\"([0-9.]+)\"");
  std::vector<std::pair<double, double>> points;
  for (auto it = std::sregex_iterator(svg.begin(), svg.end(), circle); it != std::sregex_iterator();
       ++it) {
    points.emplace_back(std::stod((*it)[1]), std::stod((*it)[2]));
  }
  ASSERT_EQ(points.size(), 6u);
  for (const std::size_t a1 : {0u, 3u}) {
    const double radius = std::hypot(points[a1].first - 240, points[a1].second - 200);
    EXPECT_GE(radius, 0.9 * 120 - 0.1) << "a1 point " << a1;
  }
  EXPECT_NE(svg.find("1.00–100.0 (log)"), std::string::npos) << svg;  // a2 spans 100x
  EXPECT_NE(svg.find("max 11.00"), std::string::npos);
  EXPECT_NE(svg.find("max 105.0"), std::string::npos);
}

TEST_F(Report, ResultsJsonCarriesTheHistogram) {
  const auto run = load_run(testing::write_sample(dir_, {}));
  ASSERT_TRUE(run.histogram);
  EXPECT_EQ(run.histogram->total(), run.latency.count);
  EXPECT_EQ(run.hardware, "AMD Ryzen 7 5800X");
  EXPECT_EQ(run.hardware_category, "workstation");
  EXPECT_FALSE(run.power_w);
  EXPECT_FALSE(run.power_note.empty());  // why there is no power figure

  testing::SampleRun later;
  later.start_unix_ns += 1'000'000'000;
  const auto with_power = load_run(testing::write_sample(dir_, later, false, 12.5));
  EXPECT_EQ(with_power.power_w, 12.5);
  EXPECT_TRUE(with_power.energy_j);
  EXPECT_EQ(with_power.power_note, "rapl:package-0");
  EXPECT_EQ(with_power.warnings, std::vector<std::string>{"governor: CPU governor is powersave"});

  auto j = with_power.json;
  j["power"] = {{"available", false},
                {"unavailable_reason", "no RAPL, hwmon or NVML source"},
                {"total", nullptr},
                {"sources", nlohmann::json::array()}};
  std::ofstream(dir_ / "unavailable.json") << j.dump();
  const auto without = load_run(dir_ / "unavailable.json");
  EXPECT_FALSE(without.power_w);
  EXPECT_EQ(without.power_note, "no RAPL, hwmon or NVML source");
}

TEST_F(Report, HtmlHasSummaryBarsTablesDistributionsAndComparison) {
  write_two_machines(10.0, 10.2);
  ReportInput input = load_report_inputs({dir_, published_a1()});
  ASSERT_EQ(input.runs.size(), 4u);
  ASSERT_EQ(input.published.size(), 1u);
  ReportOptions options;
  options.compare = std::pair{"AMD Ryzen 7 5800X", "Intel Core i7-12700H"};
  const std::string html = render_html(input, options);
  // No radar unless asked; a1's p50 bars, and its maxima beside the published rows'.
  EXPECT_EQ(count(html, "<svg class=\"radar\""), 0u);
  EXPECT_EQ(count(html, "<svg class=\"barchart\""), 2u);
  EXPECT_NE(html.find("data-figure=\"p50\""), std::string::npos);
  EXPECT_NE(html.find("data-figure=\"max\""), std::string::npos);
  EXPECT_EQ(count(html, "<svg class=\"cdf\""), 1u);
  EXPECT_NE(html.find("from the per-message CSV"), std::string::npos);
  EXPECT_NE(html.find("from the stored histogram"), std::string::npos);
  EXPECT_NE(html.find("p50 "), std::string::npos);
  EXPECT_NE(html.find("p99 "), std::string::npos);
  for (const char* table : {"at-a-glance", "versus-published", "runs", "published", "flagged",
                            "comparison", "machines"})
    EXPECT_NE(html.find("<table class=\"" + std::string(table) + "\""), std::string::npos) << table;
  // 40 rows of the published a1 file break the rules: said, and listed.
  EXPECT_NE(html.find("40 of 308 published rows break the measurement rules"), std::string::npos);
  // Self-contained: one inline script (the filters), no external resource.
  EXPECT_EQ(count(html, "<script>"), 1u);
  EXPECT_EQ(html.find("src="), std::string::npos);
  EXPECT_EQ(html.find("href="), std::string::npos);
  EXPECT_EQ(std::regex_search(html, std::regex("https?://(?!www\\.w3\\.org/2000/svg)")), false);
  // The comparison: B twice as slow with little spread is significant.
  const std::regex row("<td>a1</td><td>latency max \\(ms\\)</td>.*?significant: B worse");
  EXPECT_TRUE(std::regex_search(html, row));
  // Run-rule warnings recorded in the results are repeated.
  EXPECT_NE(html.find("governor: CPU governor is powersave"), std::string::npos);
  // Published hardware is plotted beside local runs.
  EXPECT_NE(html.find("Intel i7-12700H (RobotPerf)"), std::string::npos);

  const std::string md = render_markdown(input, options);
  for (const auto& r : input.runs) {
    EXPECT_NE(html.find(r.stem()), std::string::npos);
    EXPECT_NE(md.find(r.stem()), std::string::npos);
  }
  EXPECT_NE(md.find("## Comparison"), std::string::npos);
  EXPECT_NE(md.find("significant: B worse"), std::string::npos);
  EXPECT_NE(md.find("| configuration | max latency ms | 95 % interval |"), std::string::npos);
  EXPECT_NE(md.find("## Summary"), std::string::npos);
  EXPECT_NE(md.find("## Machines"), std::string::npos);
}

// n5: a run through the WireGuard tunnel and one without are two series (never pooled), named by
// the path, and the published n5 rows are plotted beside them.
TEST_F(Report, VpnRunsAreTheirOwnSeriesBesidePublishedN5Rows) {
  testing::SampleRun s;
  s.id = "n5";
  s.name = "n5_intra_network_vpn";
  s.rmw = "fastdds";
  s.base_latency_ms = 0.5;
  for (const bool tunnel : {true, false}) {
    auto run = testing::make_run(s);
    if (tunnel) {
      harness::NetworkLink::Description d;
      d.layout.vpn = harness::NetworkLayout::Vpn::kWireguard;
      d.layout.topology = harness::NetworkLayout::Topology::kRouted;
      d.mtu = 1420;
      d.tunnel = harness::NetworkLink::Tunnel{"wireguard-go", "0.0.20220316", "10.200.1.1",
                                              "10.200.2.2", 1500};
      run.network_link = harness::RunResult::LinkUse{d, {}};
      // As --netns records it: the pong's host behind its launcher.
      run.host_launchers = {{"remote", "ip netns exec robotperf-1-b"}};
    }
    const auto j = result_to_json(run, testing::make_machine(s));
    std::ofstream(dir_ / (std::string(tunnel ? "vpn" : "plain") + ".json")) << j.dump(2);
    s.start_unix_ns += 60'000'000'000;
  }
  const auto published_n5 = shared_data("robotperf/middleware/n5_intra_network_vpn/benchmark.yaml");
  const ReportInput input = load_report_inputs({dir_, published_n5});
  ASSERT_EQ(input.runs.size(), 2u);
  std::set<std::string> paths;
  for (const auto& r : input.runs) paths.insert(r.network);
  EXPECT_EQ(paths, (std::set<std::string>{"plain", "wireguard-go 0.0.20220316, MTU 1420, routed"}));
  ASSERT_EQ(input.published.size(), 1u);
  const std::string html = render_html(input, {});
  EXPECT_NE(html.find("wireguard-go 0.0.20220316, MTU 1420, routed"), std::string::npos);
  EXPECT_NE(html.find("Intel i7-8700K (server) &lt;-&gt; AMD Ryzen 5 PRO 4650G (client)"),
            std::string::npos);
}

TEST_F(Report, OverlappingRunsAreNotSignificant) {
  write_two_machines(5.2, 4.9);
  ReportOptions options;
  options.compare = std::pair{"AMD Ryzen 7 5800X", "Intel Core i7-12700H"};
  const std::string md = render_markdown(load_report_inputs({dir_}), options);
  for (const char* metric : {"latency max", "latency mean", "latency p50"}) {
    const std::regex row("\\| a1 \\| " + std::string(metric) +
                         " \\(ms\\) \\|[^\\n]*\\| not significant");
    EXPECT_TRUE(std::regex_search(md, row)) << metric << "\n" << md;
  }
}

// Six or more runs a side (a --repeat series each): the medians' 95 % intervals decide, and the
// table shows them.
TEST_F(Report, RepeatedSeriesAreJudgedByTheMediansIntervals) {
  int64_t t = 1'790'000'000'000'000'000;
  auto series = [&](const std::string& cpu, double base, double step) {
    for (int k = 0; k < 6; ++k) {
      testing::SampleRun s;
      s.cpu = cpu;
      s.base_latency_ms = base + step * k;
      s.start_unix_ns = (t += 60'000'000'000);
      testing::write_sample(dir_, s);
    }
  };
  series("AMD Ryzen 7 5800X 8-Core Processor", 5.0, 0.1);         // 5.0 .. 5.5
  series("Intel(R) Core(TM) i7-12700H CPU @ 2.30GHz", 7.0, 0.1);  // 7.0 .. 7.5
  series("Intel(R) Xeon(R) CPU E5-2680 v4 @ 2.40GHz", 5.2, 0.1);  // 5.2 .. 5.7
  const auto input = load_report_inputs({dir_});
  ReportOptions options;
  options.compare = std::pair{"AMD Ryzen 7 5800X", "Intel Core i7-12700H"};
  std::string md = render_markdown(input, options);
  EXPECT_TRUE(std::regex_search(
      md, std::regex("\\| a1 \\| latency p50 \\(ms\\) \\| [0-9.]+ \\[[0-9.]+, [0-9.]+\\] \\|[^\\n]*"
                     "significant: B worse \\(the medians' 95 % intervals do not overlap\\)")))
      << md;
  options.compare = std::pair{"AMD Ryzen 7 5800X", "Intel Xeon CPU E5-2680 v4"};
  md = render_markdown(input, options);
  EXPECT_TRUE(std::regex_search(md, std::regex("\\| a1 \\| latency p50 \\(ms\\) \\|[^\\n]*"
                                               "within run-to-run noise")))
      << md;
}

TEST_F(Report, InvalidRunsAreWarnedAboutAndNotPlotted) {
  testing::SampleRun bad;
  bad.lost = 10;
  bad.cpu = "Lossy CPU";
  bad.start_unix_ns += 1'000'000'000;
  testing::write_sample(dir_, bad);
  testing::write_sample(dir_, {});
  const auto input = load_report_inputs({dir_});
  const std::string html = render_html(input, {});
  EXPECT_NE(html.find("is INVALID: lost messages"), std::string::npos);
  EXPECT_TRUE(std::regex_search(html, std::regex("<tr class=\"warn\"[^>]*><td>a1-intra")));
  // Only the valid run's series is in the radar's legend.
  EXPECT_NE(html.find("AMD Ryzen 7 5800X · intra · 30 Hz<title>"), std::string::npos);
  EXPECT_EQ(html.find("Lossy CPU · intra · 30 Hz<title>"), std::string::npos);
  // Its latency curve is drawn apart: grey, dashed, labelled INVALID.
  const std::regex invalid_curve(
      "<polyline class=\"curve invalid\" data-series=\"[^\"]*\" fill=\"none\" stroke=\"#999999\"");
  EXPECT_EQ(std::distance(std::sregex_iterator(html.begin(), html.end(), invalid_curve),
                          std::sregex_iterator()),
            1);
  EXPECT_NE(html.find(" (INVALID) — from the "), std::string::npos);
}

// A machine's warnings are said once for all its runs, a run's own under that run, and INVALID
// runs come first, in view; the rest is folded behind one summary line.
TEST_F(Report, WarningsAreGroupedByMachineAndRunBehindOneLine) {
  testing::SampleRun run;
  run.warnings = {{"virtual_machine", "running in a virtual machine"},
                  {"samples", "90 measured messages"}};
  for (int i = 0; i < 3; ++i) {
    run.start_unix_ns += 60'000'000'000;
    testing::write_sample(dir_, run);
  }
  testing::SampleRun bad = run;
  bad.lost = 10;
  bad.start_unix_ns += 60'000'000'000;
  testing::write_sample(dir_, bad);
  const auto input = load_report_inputs({dir_});
  const std::string html = render_html(input, {});
  EXPECT_EQ(count(html, "virtual_machine: running in a virtual machine"), 1u) << html;
  EXPECT_NE(html.find("virtual_machine: running in a virtual machine (4 runs)"), std::string::npos);
  EXPECT_EQ(count(html, "samples: 90 measured messages"), 4u) << "a run's own, under each run";
  EXPECT_NE(html.find("<strong>Validity:</strong> 1 INVALID run · 1 machine warning (1 machine) "
                      "· 4 run warnings"),
            std::string::npos)
      << html.substr(0, 3000);
  const auto invalid = html.find("<ul class=\"invalid\">");
  const auto folded = html.find("<details>");
  ASSERT_NE(invalid, std::string::npos);
  ASSERT_NE(folded, std::string::npos);
  EXPECT_LT(invalid, folded) << "INVALID runs before the folded warnings";
  EXPECT_LT(html.find("is INVALID: lost messages"), folded);
  const std::string md = render_markdown(input, {});
  EXPECT_NE(md.find("## Validity\n\n1 INVALID run"), std::string::npos) << md.substr(0, 2000);
  EXPECT_EQ(count(md, "virtual_machine: running in a virtual machine (4 runs)"), 1u);
}

// A 30 Hz run says only that the graph kept up with 30 Hz: where a peak search found its limit,
// the throughput radar shows the peak, named so on every plot, and never pools the two.
TEST_F(Report, ThroughputRadarUsesPeaksWhereFoundAndNamesThemOneWay) {
  testing::write_sample(dir_, {});
  testing::SampleRun peak_run;
  peak_run.start_unix_ns += 1'000'000'000;
  const auto peak_path = testing::write_sample(dir_, peak_run);
  auto j = nlohmann::json::parse(read_text(peak_path));
  j["throughput"]["kind"] = "peak";
  j["throughput"]["output_hz"] = 163.0;
  std::ofstream(peak_path) << j.dump();
  testing::SampleRun other;
  other.cpu = "Intel Core i7-12700H";
  other.start_unix_ns += 2'000'000'000;
  testing::write_sample(dir_, other);

  const auto input = load_report_inputs({dir_});
  EXPECT_EQ(std::ranges::count(input.runs, std::string("peak"), &StoredRun::throughput_kind), 1);
  ReportOptions options;
  options.radar = true;
  const detail::Model model = detail::build_model(input, options);
  const auto& radars = model.radars.at("perception");
  const auto throughput =
      std::ranges::find(radars, std::string("throughput"), &detail::Radar::metric);
  ASSERT_NE(throughput, radars.end());
  // The peak run has one name on the page: its configuration's, with "peak" for its rate.
  EXPECT_EQ(throughput->series, (std::vector<std::string>{"AMD Ryzen 7 5800X · intra · peak",
                                                          "Intel Core i7-12700H · intra · 30 Hz"}));
  const auto p50 = model.benchmarks.at("perception").at(0).charts.at(0);
  EXPECT_TRUE(std::ranges::any_of(p50.bars, [](const detail::Bar& b) {
    return b.series == "AMD Ryzen 7 5800X · intra · peak";
  }));
}

// A series keeps its colour on every plot of the page, and series left out of a radar are in the
// table below it, as its legend says.
TEST_F(Report, SeriesKeepTheirColourAndOmittedOnesAreInTheTable) {
  write_two_machines(9.0, 9.5);
  ReportOptions options;
  options.radar = true;
  options.max_radar_series = 1;
  const std::string html = render_html(load_report_inputs({dir_}), options);
  EXPECT_NE(html.find("+ 1 more platforms (in the table below)"), std::string::npos);
  EXPECT_NE(html.find("(not plotted)</td>"), std::string::npos);
  // The first series is drawn in the palette's first colour in the latency and the throughput
  // radar alike; no radar draws another series in it.
  const std::regex polygon(
      "<rect class=\"bar\" [^>]* fill=\"(#[0-9a-f]{6})\" fill-opacity=\"0.85\"");
  std::set<std::string> colours;
  for (auto it = std::sregex_iterator(html.begin(), html.end(), polygon);
       it != std::sregex_iterator(); ++it) {
    colours.insert((*it)[1]);
  }
  EXPECT_EQ(colours, std::set<std::string>{"#0072b2"}) << "one series, one colour";
}

// A series without a value on an axis has a gap there: no line joins the axes either side of it.
TEST_F(Report, AMissingValueIsAGapNotALineAcrossIt) {
  int64_t t = 1'790'000'000'000'000'000;
  for (const char* id : {"a1", "a2", "a3"}) {
    for (const char* cpu : {"Full CPU", "Gappy CPU"}) {
      if (std::string(cpu) == "Gappy CPU" && std::string(id) == "a3") continue;
      testing::SampleRun run;
      run.id = id;
      run.name = std::string(id) + "_bench";
      run.cpu = cpu;
      run.start_unix_ns = (t += 60'000'000'000);
      testing::write_sample(dir_, run);
    }
  }
  ReportOptions options;
  options.radar = true;
  const std::string html = render_html(load_report_inputs({dir_}), options);
  // Per radar: the full series a polygon, the gappy one a single line from a1 to a2.
  const std::size_t polygons = count(html, "<polygon class=\"series\"");
  EXPECT_GE(polygons, 2u);
  EXPECT_EQ(count(html, "<line class=\"series-part\""), polygons) << html;
}

// A radar scales each axis to its own values: one series (or one value per axis) would be a
// polygon on the rim saying nothing, so it is drawn as bars; an axis with a single value among
// others puts it mid-way and says "only", not on the rim where it would read as the worst.
TEST_F(Report, SingleValuesAreNeverDrawnAsTheWorst) {
  int64_t t = 1'790'000'000'000'000'000;
  for (const char* id : {"a1", "a2", "a3"}) {
    testing::SampleRun run;
    run.id = id;
    run.name = std::string(id) + "_bench";
    run.start_unix_ns = (t += 60'000'000'000);
    testing::write_sample(dir_, run);
  }
  ReportOptions options;
  options.radar = true;
  const std::string single = render_html(load_report_inputs({dir_}), options);
  EXPECT_EQ(count(single, "<svg class=\"radar\""), 0u);
  EXPECT_EQ(count(single, "<svg class=\"bars\""), 2u);  // latency and throughput
  EXPECT_NE(single.find("or one value per benchmark, make no radar"), std::string::npos);

  testing::SampleRun other;
  other.id = "a1";
  other.name = "a1_bench";
  other.cpu = "Other CPU";
  other.base_latency_ms = 9;
  other.start_unix_ns = (t += 60'000'000'000);
  testing::write_sample(dir_, other);
  const std::string two = render_html(load_report_inputs({dir_}), options);
  EXPECT_EQ(count(two, "<svg class=\"radar\""), 2u);
  // a1 has two values and a real scale; a2 and a3 have one each, written as such.
  EXPECT_EQ(count(two, ">only "), 4u) << two;
  EXPECT_EQ(count(two, "class=\"axis-scale\" x=\""), 6u);
  const std::regex scale_max("class=\"axis-scale\"[^>]*>max ");
  EXPECT_EQ(std::distance(std::sregex_iterator(two.begin(), two.end(), scale_max),
                          std::sregex_iterator()),
            2);
}

// Published rows state the rate they were measured at ("bounded to 30fps", "swept from 30 to
// 300 fps"): a local run at another rate is named beside the plot, the published table lists
// the rates, and --compare rate= selects published rows by it.
TEST_F(Report, PublishedRowsAreMatchedOnTheirStatedRate) {
  testing::SampleRun run;
  testing::write_sample(dir_, run);
  const auto input = load_report_inputs({dir_, published_a1()});
  const std::string md = render_markdown(input, {});
  EXPECT_NE(md.find("Not alike: a1: the published rows state 30 Hz, 30-300 Hz sweep, 30-500 Hz "
                    "sweep, the local runs ran at 30 Hz (--compare rate=HZ picks one)"),
            std::string::npos)
      << md.substr(0, 4000);
  EXPECT_NE(md.find("| rates stated |"), std::string::npos);
  // One published configuration: the i7-12700H's black-box rows at 30 Hz.
  ReportOptions options;
  options.compare = std::pair{std::string("rmw=intra"),
                              std::string("hardware=Intel i7-12700H,mode=black,rate=30")};
  const std::string compared = render_markdown(input, options);
  EXPECT_NE(compared.find("B = hardware=Intel i7-12700H,mode=black,rate=30: 0 local runs, 3 "
                          "published rows"),
            std::string::npos)
      << compared.substr(compared.find("## Comparison"));
  // Its rows at 30 Hz and its sweeps are two configurations: never one median.
  options.compare = std::pair{std::string("rmw=intra"), std::string("Intel i7-12700H")};
  try {
    render_markdown(input, options);
    ADD_FAILURE() << "a side pooling two published configurations was accepted";
  } catch (const ReportError& e) {
    const std::string why = e.what();
    EXPECT_NE(why.find("Intel i7-12700H (RobotPerf) · black · 30 Hz; Intel i7-12700H (RobotPerf) "
                       "· black · 30-500 Hz sweep"),
              std::string::npos)
        << why;
  }
  // Nor local runs with published rows.
  options.compare = std::pair{std::string("Intel i7-12700H"), std::string("mode=black,rate=30")};
  EXPECT_THROW(render_markdown(input, options), ReportError);
}

// What the terminal summary shows beside the latency is on the page too: the functional check,
// the graph's CPU and memory, energy per message, the control loops and the grey-box hops.
TEST_F(Report, RunsShowWhatElseTheyMeasured) {
  const auto path = testing::write_sample(dir_, {});
  auto j = nlohmann::json::parse(read_text(path));
  j["functional"] = {{"valid", true},
                     {"metrics", {{"mae_px", {{"value", 0.0861}, {"unit", "px"}}}}}};
  j["resources"]["processes"] = {{{"cpu_percent", 40.0}, {"peak_rss_bytes", 100 << 20}},
                                 {{"cpu_percent", 2.5}, {"peak_rss_bytes", 20 << 20}}};
  j["control_loops"] = {{{"node", "controller_manager"},
                         {"cycles", 60000},
                         {"deadline_misses", 0},
                         {"period_jitter_us", {{"p99", 12.34}}}}};
  j["grey"]["hops"] = {{{"label", "rectify: image_proc/rectify"},
                        {"kind", "kernel"},
                        {"duration_ms", {{"mean", 2.25}, {"p50", 1.75}, {"p99", 5.5}}}}};
  j["grey"]["callbacks"] = {
      {{"node", "rectify"},
       {"source", "/camera/image_raw"},
       {"duration_ms", {{"count", 68}, {"mean", 1.5}, {"p50", 1.25}, {"p99", 4.5}, {"max", 7.0}}}}};
  j["peak_search"] = {{"steps",
                       {{{"rate_hz", 30.0},
                         {"offered_hz", 30.0},
                         {"output_hz", 30.0},
                         {"loss_percent", 0.0},
                         {"latency_ms", 4.5},
                         {"passed", true},
                         {"reason", ""}},
                        {{"rate_hz", 60.0},
                         {"offered_hz", 60.0},
                         {"output_hz", 41.0},
                         {"loss_percent", 31.6},
                         {"latency_ms", 80.25},
                         {"passed", false},
                         {"reason", "loss 31.6 % > 0 %"}}}},
                      {"stop_reason", "the failing rate is within 5 % of the sustained one"}};
  j["power"] = {{"available", true}, {"average_w", 12.5}, {"energy_j", 0.625}};
  std::ofstream(path) << j.dump();
  const auto input = load_report_inputs({dir_});
  const std::string md = render_markdown(input, {});
  const std::string html = render_html(input, {});
  EXPECT_NE(md.find("| 2 | 60.0 | 60.0 | 41.0 | 31.60 | 80.250 | failed: loss 31.6 % > 0 % (the "
                    "failing rate is within 5 % of the sustained one) |"),
            std::string::npos)
      << md;
  EXPECT_NE(html.find("<table class=\"peak-search\""), std::string::npos);
  EXPECT_NE(md.find("| rectify | /camera/image_raw | 68 | 1.500 | 1.250 | 4.500 | 7.000 |"),
            std::string::npos)
      << md;
  EXPECT_NE(html.find("<table class=\"callbacks\""), std::string::npos);
  EXPECT_NE(html.find("<td>VALID: mae_px 0.0861 px</td><td class=\"num\">42.5</td><td "
                      "class=\"num\">120.0</td><td class=\"num\">6.250</td>"),
            std::string::npos);
  // The hops as bars too, mean with a whisker to p99.
  EXPECT_NE(html.find("<svg class=\"hops\""), std::string::npos);
  EXPECT_NE(html.find("rectify: image_proc/rectify: mean 2.25 ms"), std::string::npos);
  EXPECT_NE(md.find("| VALID: mae_px 0.0861 px | 42.5 | 120.0 | 6.250 |"), std::string::npos) << md;
  EXPECT_NE(md.find("| rectify: image_proc/rectify | kernel | 2.250 | 1.750 | 5.500 |"),
            std::string::npos)
      << md;
  EXPECT_NE(md.find("controller_manager: period jitter p99 12.3 us, 0 deadline misses in 60000 "
                    "cycles"),
            std::string::npos)
      << md;
}

// A comparison compares one configuration with one: sides are chosen by fields, and a side that
// would pool two configurations of a benchmark is refused, naming them.
TEST_F(Report, CompareSelectsByFieldsAndRefusesToPoolConfigurations) {
  for (const char* rmw : {"intra", "fastdds"}) {
    for (int i = 0; i < 2; ++i) {
      testing::SampleRun run;
      run.rmw = rmw;
      run.base_latency_ms = std::string(rmw) == "intra" ? 5.0 : 9.0;
      run.start_unix_ns +=
          (std::string(rmw) == "intra" ? 0 : 10) * 1'000'000'000LL + i * 1'000'000'000LL;
      testing::write_sample(dir_, run);
    }
  }
  const auto input = load_report_inputs({dir_});
  ReportOptions options;
  options.compare = std::pair{"rmw=intra", "hardware=AMD Ryzen 7 5800X,rmw=fastdds,rate=30"};
  const std::string md = render_markdown(input, options);
  EXPECT_NE(md.find("A = rmw=intra: 2 local runs"), std::string::npos) << md;
  EXPECT_NE(md.find("B = hardware=AMD Ryzen 7 5800X,rmw=fastdds,rate=30: 2 local runs"),
            std::string::npos)
      << md;
  options.compare = std::pair{"AMD Ryzen 7 5800X", "rmw=fastdds"};
  try {
    render_markdown(input, options);
    ADD_FAILURE() << "a side of intra and fastdds runs was compared";
  } catch (const ReportError& e) {
    EXPECT_NE(std::string(e.what()).find("selects 2 configurations of a1 (AMD Ryzen 7 5800X · "
                                         "fastdds · 30 Hz; AMD Ryzen 7 5800X · intra · 30 Hz)"),
              std::string::npos)
        << e.what();
  }
  options.compare = std::pair{"rmw=intra", "colour=blue"};
  EXPECT_THROW(render_markdown(input, options), ReportError);
}

// A control benchmark's run goes at its input rate with its controller loop at another (c3: 50
// and 100 Hz); the notes name the loop's, as published rows do, so rate= picks it by either.
TEST_F(Report, CompareRateSelectsAControlRunByItsLoopRateToo) {
  const auto path = testing::write_sample(dir_, {});
  auto j = nlohmann::json::parse(read_text(path));
  j["control_loops"] = {{{"node", "controller_manager"}, {"update_rate_hz", 100.0}}};
  std::ofstream(path) << j.dump();
  const auto input = load_report_inputs({dir_});
  ReportOptions options;
  options.compare = std::pair{"rate=100", "rate=30"};
  const std::string md = render_markdown(input, options);
  EXPECT_NE(md.find("A = rate=100: 1 local runs"), std::string::npos) << md;
  EXPECT_NE(md.find("B = rate=30: 1 local runs"), std::string::npos) << md;
  options.compare = std::pair{"rate=100", "rate=50"};
  EXPECT_THROW(render_markdown(input, options), ReportError);
}

// A valid black-box run of `id` on one machine, intra in one process at `rate_hz`: `messages`
// latencies of at most 2 ms, throughput at its rate.
StoredRun valid_intra_run(const std::string& id, const std::string& category, double rate_hz,
                          std::size_t messages) {
  StoredRun run;
  run.benchmark_id = id;
  run.category = category;
  run.type = "black";
  run.hardware = "AMD Ryzen 7 5800X";
  run.rmw = "intra";
  run.processes = "single";
  run.rate_hz = rate_hz;
  run.valid = true;
  run.latency.count = messages;
  run.latency.max = 2.0;
  run.throughput_hz = rate_hz;
  return run;
}

// A comparison of two unlike configurations names every difference beside the one selected, and
// makes no judgement on offered throughputs fed at different rates: each is its input rate.
TEST(Comparison, NamesTheDifferencesBesideTheSelectedOneAndJudgesNoOfferedRate) {
  ReportInput input;
  for (int i = 0; i < 3; ++i) {
    StoredRun intra = valid_intra_run("d6", "manipulation", 200, 1000);
    intra.path = "d6-intra-" + std::to_string(i) + ".json";
    intra.latency.max = 2.0 + 0.1 * i;
    intra.throughput_hz = 200.0 + 0.01 * i;
    StoredRun fastdds = intra;
    fastdds.path = "d6-fastdds-" + std::to_string(i) + ".json";
    fastdds.type = "grey";
    fastdds.rmw = "fastdds";
    fastdds.processes = "per-node";
    fastdds.rate_hz = 10;
    fastdds.throughput_hz = 10.0 + 0.01 * i;
    input.runs.push_back(intra);
    input.runs.push_back(fastdds);
  }
  const detail::Comparison c = detail::build_comparison(input, "rmw=intra", "rmw=fastdds");
  const std::string notes = joined(c.notes, "\n");
  EXPECT_NE(notes.find("Not alike: d6: "), std::string::npos) << notes;
  for (const char* difference :
       {"rate 200 Hz vs 10 Hz", "mode black vs grey", "processes single vs per-node"})
    EXPECT_NE(notes.find(difference), std::string::npos) << difference << "\n" << notes;
  EXPECT_EQ(notes.find("rmw intra vs fastdds"), std::string::npos) << "the selected difference";
  bool throughput = false;
  for (const auto& row : c.table.rows) {
    if (row[1] != "throughput (fps)") continue;
    throughput = true;
    EXPECT_EQ(row.back().find("significant"), std::string::npos) << row.back();
  }
  EXPECT_TRUE(throughput);
}

// Runs whose nodes computed with other parameters (or another plug-in's kernel) did other work:
// one side does not pool them, and two sides that differ in them say so.
TEST(Comparison, RunsWhoseNodesComputedDifferentlyAreNotAlike) {
  const StoredRun run = valid_intra_run("x5", "perception", 30, 100);
  StoredRun large = run, small = run;
  large.path = "x5-a.json";
  large.node_settings = "resize (built-in perception): scale_width=2";
  small.path = "x5-b.json";
  small.node_settings = "resize (built-in perception): scale_width=0.25";
  small.latency.max = 0.3;
  ReportInput input;
  input.runs = {large, small};
  EXPECT_THROW(detail::build_comparison(input, "x5-a", "rmw=intra"), ReportError);
  const detail::Comparison c = detail::build_comparison(input, "x5-a", "x5-b");
  EXPECT_NE(joined(c.notes, "\n")
                .find("node settings resize (built-in perception): scale_width=2 "
                      "vs resize (built-in perception): scale_width=0.25"),
            std::string::npos)
      << joined(c.notes, "\n");
}

// Published black-box and grey-box rows of one hardware are two measurements: two series and two
// rows of the published table, as local runs keep them apart, never one median of both.
TEST(Published, BlackAndGreyRowsAreSeparateSeries) {
  ReportInput input;
  PublishedBenchmark b;
  b.id = "a5";
  b.category = "perception";
  for (const auto& [type, value] : {std::pair{"black", 10.0}, {"grey", 40.0}}) {
    PublishedResult row;
    row.type = type;
    row.metric = "latency";
    row.metric_unit = "ms";
    row.hardware = "Intel i7-8700K";
    row.value = value;
    b.results.push_back(row);
  }
  input.published.push_back(b);
  ReportOptions options;
  options.radar = true;
  const detail::Model model = detail::build_model(input, options);
  const detail::Radar& latency = model.radars.at("perception").at(0);
  ASSERT_EQ(latency.metric, "latency");
  ASSERT_EQ(latency.series.size(), 2u);
  EXPECT_EQ(latency.series[0], "Intel i7-8700K (RobotPerf)");
  EXPECT_EQ(latency.series[1], "Intel i7-8700K · grey (RobotPerf)");
  EXPECT_EQ(latency.values[0][0], 10.0);
  EXPECT_EQ(latency.values[1][0], 40.0);
  const detail::Table& table = model.benchmarks.at("perception").at(0).published;
  ASSERT_EQ(table.rows.size(), 2u);
  EXPECT_EQ(table.rows[0][1], "black");
  EXPECT_EQ(table.rows[0][4], "10.00");
  EXPECT_EQ(table.rows[1][1], "grey");
  EXPECT_EQ(table.rows[1][4], "40.00");
}

// A results file from elsewhere may hold part of what ours do: a CPU frequency range without its
// top is shown open, not read past the end of the object.
TEST_F(Report, AFrequencyRangeWithoutItsMaximumIsShownOpen) {
  const auto path = testing::write_sample(dir_, {});
  auto j = nlohmann::json::parse(read_text(path));
  j["machine"]["cpu"]["frequency"] = {{"min_khz", 800000}};
  std::ofstream(path) << j.dump();
  const std::string md = render_markdown(load_report_inputs({dir_}), {});
  EXPECT_NE(md.find("| 800–? |"), std::string::npos) << md.substr(0, 3000);
}

// Local runs and published rows on one axis that cannot be the same measurement are said to be
// so beside the plot: another type, or medians orders of magnitude apart.
TEST_F(Report, UnalikeLocalAndPublishedValuesAreNamedBesideThePlot) {
  testing::SampleRun fast;
  fast.base_latency_ms = 0.01;
  testing::write_sample(dir_, fast);
  const std::string md = render_markdown(load_report_inputs({dir_, published_a1()}), {});
  EXPECT_NE(md.find("Not alike: a1: the published rows are black/grey-box measurements, the "
                    "local runs black-box"),
            std::string::npos)
      << md.substr(0, 3000);
  EXPECT_NE(md.find("Not alike: a1: local runs (median "), std::string::npos);
  EXPECT_NE(md.find("they are unlikely to measure the same thing"), std::string::npos);
}

// Four runs with the same percentiles mark them at the same spot: their labels still do not overlap
// (11 px text, about 6.5 px per character and 12 px per line).
TEST_F(Report, DistributionLabelsNeverOverlap) {
  testing::SampleRun run;
  for (int i = 0; i < 4; ++i) {
    run.start_unix_ns += 1'000'000'000;
    testing::write_sample(dir_, run);
  }
  const std::string html = render_html(load_report_inputs({dir_}), {});
  const std::regex label(
      "<text class=\"marker-label\" x=\"([0-9.]+)\" y=\"([0-9.]+)\"[^>]*>([^<]*)<");
  struct Box {
    double x, y, w;
  };
  std::vector<Box> boxes;
  for (auto it = std::sregex_iterator(html.begin(), html.end(), label);
       it != std::sregex_iterator(); ++it) {
    boxes.push_back({std::stod((*it)[1]), std::stod((*it)[2]), 6.5 * (*it)[3].length()});
  }
  ASSERT_EQ(boxes.size(), 8u);  // p50 and p99 of each run
  for (std::size_t i = 0; i < boxes.size(); ++i) {
    for (std::size_t j = 0; j < i; ++j) {
      const Box& a = boxes[i];
      const Box& b = boxes[j];
      const bool overlap = a.x < b.x + b.w && b.x < a.x + a.w && a.y - 12 < b.y && b.y - 12 < a.y;
      EXPECT_FALSE(overlap) << "labels " << j << " and " << i << " overlap";
    }
  }
}

// Runs that differ in rate, process layout, black/grey, arrivals, backend (device-resident or not)
// or how the Monitor waited are separate series, never pooled into one median.
TEST_F(Report, RunsOfDifferentConfigurationsAreSeparateSeries) {
  testing::SampleRun base;
  const auto at_60 = testing::write_sample(dir_, base);
  auto j = nlohmann::json::parse(read_text(at_60));
  j["configuration"]["rate_hz"] = 60.0;
  std::ofstream(at_60) << j.dump();
  base.start_unix_ns += 1'000'000'000;
  const auto per_node = testing::write_sample(dir_, base);
  j = nlohmann::json::parse(read_text(per_node));
  j["configuration"]["processes"] = "per-node";
  j["type"] = "grey";
  std::ofstream(per_node) << j.dump();
  base.start_unix_ns += 1'000'000'000;
  const auto accelerated = testing::write_sample(dir_, base);
  j = nlohmann::json::parse(read_text(accelerated));
  j["nodes"] = {{{"name", "rectify"}, {"kernel", "image_proc/rectify"}, {"backend", "opencl"}},
                {{"name", "resize"}, {"kernel", "image_proc/resize"}, {"backend", "cpu"}}};
  std::ofstream(accelerated) << j.dump();
  base.start_unix_ns += 1'000'000'000;
  const auto spinning = testing::write_sample(dir_, base);
  j = nlohmann::json::parse(read_text(spinning));
  j["configuration"]["monitor_wait"] = "spin";
  std::ofstream(spinning) << j.dump();
  base.start_unix_ns += 1'000'000'000;
  // The same nodes on cuda, once with messages in host memory and once device-resident.
  for (const bool resident : {false, true}) {
    const auto on_cuda = testing::write_sample(dir_, base);
    j = nlohmann::json::parse(read_text(on_cuda));
    j["nodes"] = {{{"name", "rectify"}, {"kernel", "image_proc/rectify"}, {"backend", "cuda"}},
                  {{"name", "resize"}, {"kernel", "image_proc/resize"}, {"backend", "cuda"}}};
    j["configuration"]["device_resident"] = nlohmann::json::array();
    if (resident) {
      j["configuration"]["device_resident"].push_back({{"topic", "/rectify/image_rect"},
                                                       {"from", "rectify"},
                                                       {"to", {"resize"}},
                                                       {"backend", "cuda"}});
    }
    std::ofstream(on_cuda) << j.dump();
    base.start_unix_ns += 1'000'000'000;
  }
  testing::write_sample(dir_, base);
  const std::string html = render_html(load_report_inputs({dir_}), {});
  for (const std::string series :
       {"AMD Ryzen 7 5800X · intra · 60 Hz", "AMD Ryzen 7 5800X · intra · per-node · grey · 30 Hz",
        "AMD Ryzen 7 5800X · intra · opencl · 30 Hz",
        "AMD Ryzen 7 5800X · intra · monitor spinning · 30 Hz",
        "AMD Ryzen 7 5800X · intra · cuda · 30 Hz",
        "AMD Ryzen 7 5800X · intra · cuda-resident · 30 Hz", "AMD Ryzen 7 5800X · intra · 30 Hz"}) {
    // Each a bar of its own, an entry of the key and a latency curve.
    EXPECT_EQ(count(html, "data-series=\"" + series + "\""), 3u) << series;
  }
}

TEST_F(Report, OldResultsWithoutHistogramUseTheStoredPercentiles) {
  const auto path = testing::write_sample(dir_, {});
  auto j = nlohmann::json::parse(read_text(path));
  j["latency_ms"].erase("from_scheduled_histogram");
  std::ofstream(path) << j.dump();
  const std::string html = render_html(load_report_inputs({dir_}), {});
  EXPECT_NE(html.find("from the stored percentiles"), std::string::npos);
}

TEST_F(Report, ResultsWithoutMachineOrSoftwareStillReport) {
  const auto path = testing::write_sample(dir_, {});
  auto j = nlohmann::json::parse(read_text(path));
  j.erase("machine");
  j.erase("software");
  std::ofstream(path) << j.dump();
  const auto input = load_report_inputs({dir_});
  ASSERT_EQ(input.runs.size(), 1u);
  EXPECT_EQ(input.runs[0].hardware, "unknown machine");
  EXPECT_NE(render_html(input, {}).find("<table class=\"machines\""), std::string::npos);
  EXPECT_EQ(export_entries(input.runs[0], {}).size(), 2u);
}

TEST_F(Report, AFileWithAWrongTypedFieldIsSkippedNamingTheField) {
  write_two_machines(10, 11);
  const auto path = testing::write_sample(dir_, {});
  auto j = nlohmann::json::parse(read_text(path));
  j["counts"]["measured"] = "many";
  std::ofstream(path) << j.dump();
  const RunScan scan = scan_results(dir_);
  EXPECT_EQ(scan.runs.size(), 4u);  // the others are read
  ASSERT_EQ(scan.skipped.size(), 1u);
  EXPECT_NE(scan.skipped[0].find(path.filename().string()), std::string::npos) << scan.skipped[0];
  EXPECT_NE(scan.skipped[0].find("counts.measured is \"many\""), std::string::npos)
      << scan.skipped[0];
  EXPECT_EQ(load_report_inputs({dir_}).runs.size(), 4u);
}

// A hardware name holding '=' is a name, not fields: the automatic comparison and a comparison
// asked by that name find its runs (the report stopped with "is not a field=value").
TEST_F(Report, AHardwareNameWithAnEqualsSignIsAName) {
  testing::SampleRun a;
  a.cpu = "ACME x=1";
  testing::write_sample(dir_, a, false, 40);
  testing::SampleRun b;
  b.cpu = "ACME y=2";
  b.start_unix_ns += 60'000'000'000;
  testing::write_sample(dir_, b, false, 41);
  const auto input = load_report_inputs({dir_});
  ASSERT_EQ(input.runs.size(), 2u);
  EXPECT_NE(render_html(input, {}).find("ACME x=1"), std::string::npos);
  ReportOptions options;
  options.compare = std::pair{"ACME x=1", "ACME y=2"};
  const std::string md = render_markdown(input, options);
  EXPECT_EQ(md.find("no benchmark and metric in common"), std::string::npos) << md;
  EXPECT_NE(md.find("ACME x=1"), std::string::npos) << md;
}

// The page opens on what was run and what it found: the summary comes before any benchmark, and
// names the fastest configuration of each benchmark.
TEST_F(Report, TheSummaryComesFirstWithTheFindings) {
  write_two_machines(10.0, 10.2);
  const auto input = load_report_inputs({dir_, published_a1()});
  const detail::Model model = detail::build_model(input, {});
  ASSERT_FALSE(model.findings.empty());
  EXPECT_LE(model.findings.size(), 5u);
  EXPECT_EQ(model.findings.front(),
            "Fastest configuration (p50 latency): AMD Ryzen 7 5800X · intra · 30 Hz in a1.");
  ASSERT_EQ(model.at_a_glance.rows.size(), 1u);
  EXPECT_EQ(model.at_a_glance.rows[0][0], "a1");
  EXPECT_EQ(model.at_a_glance.rows[0][1], "4 of 4");
  EXPECT_EQ(model.at_a_glance.rows[0][3], "AMD Ryzen 7 5800X · intra · 30 Hz");
  EXPECT_NE(
      model.overview.front().find("Ran 4 runs (4 valid) of 1 benchmark (a1) in 2 "
                                  "configurations on AMD Ryzen 7 5800X, Intel Core i7-12700H"),
      std::string::npos)
      << model.overview.front();
  const std::string html = render_html(input, {});
  const auto summary = html.find("<section class=\"summary\"");
  ASSERT_NE(summary, std::string::npos);
  EXPECT_LT(summary, html.find("<h2 id=\"category-"));
  EXPECT_LT(summary, html.find("<svg"));
}

// A --repeat series is one configuration: one bar at the median of its runs' p50s, each run a
// point, the median's 95 % interval as whiskers; bars are sorted, the fastest first.
TEST_F(Report, ARepeatSeriesIsOneBarWithItsRunsAndBarsAreSorted) {
  int64_t t = 1'790'000'000'000'000'000;
  for (int k = 0; k < 6; ++k) {
    testing::SampleRun s;
    s.base_latency_ms = 8.0 + 0.1 * k;
    s.start_unix_ns = (t += 60'000'000'000);
    testing::write_sample(dir_, s);
  }
  testing::SampleRun fast;
  fast.cpu = "Fast CPU";
  fast.base_latency_ms = 2.0;
  fast.start_unix_ns = (t += 60'000'000'000);
  testing::write_sample(dir_, fast);
  const auto input = load_report_inputs({dir_});
  const detail::Model model = detail::build_model(input, {});
  const auto& charts = model.benchmarks.at("perception").at(0).charts;
  ASSERT_EQ(charts.size(), 1u);  // no published rows: no maximum beside them
  const auto& bars = charts[0].bars;
  ASSERT_EQ(bars.size(), 2u);
  EXPECT_EQ(bars[0].series, "Fast CPU · intra · 30 Hz");
  EXPECT_EQ(bars[1].series, "AMD Ryzen 7 5800X · intra · 30 Hz");
  EXPECT_EQ(bars[1].points.size(), 6u);
  EXPECT_EQ(bars[1].count, "6 runs");
  // The runs table names each run's configuration as its bar does.
  const auto& runs = model.benchmarks.at("perception").at(0).runs;
  ASSERT_EQ(runs.header[1], "configuration");
  ASSERT_EQ(runs.rows.size(), 7u);
  for (std::size_t i = 0; i < 6; ++i) EXPECT_EQ(runs.rows[i][1], bars[1].series);
  EXPECT_EQ(runs.rows[6][1], bars[0].series);  // the fast run ran last
  std::vector<double> p50s;
  for (const auto& r : input.runs) {
    if (r.hardware != "Fast CPU") p50s.push_back(r.latency.p50);
  }
  EXPECT_DOUBLE_EQ(bars[1].value, metrics::median(p50s));
  ASSERT_TRUE(std::isfinite(bars[1].lower) && std::isfinite(bars[1].upper));
  EXPECT_LE(bars[1].lower, bars[1].value);
  EXPECT_GE(bars[1].upper, bars[1].value);
  // One run: the interval of its own p50, as its results file states it.
  EXPECT_TRUE(bars[0].points.empty());
  EXPECT_TRUE(std::isfinite(bars[0].lower) && std::isfinite(bars[0].upper));
  const std::string svg = detail::bar_chart_svg(charts[0]);
  EXPECT_EQ(count(svg, "<circle class=\"run\""), 6u);
  EXPECT_EQ(count(svg, "<path class=\"whisker\""), 2u);
  EXPECT_LT(svg.find("data-series=\"Fast CPU"), svg.find("data-series=\"AMD Ryzen"));
  // The figure is named on the axis: never "latency" alone.
  EXPECT_NE(svg.find(">p50 latency (ms)<title>"), std::string::npos);
}

// RobotPerf reports the maximum latency: the published rows are drawn beside the local maxima,
// hatched, never beside a p50; the table compares like with like, without flagged rows.
TEST_F(Report, PublishedRowsArePlottedAndComparedLikeWithLike) {
  testing::write_sample(dir_, {});
  const auto input = load_report_inputs({dir_, published_a1()});
  const detail::Model model = detail::build_model(input, {});
  const auto& section = model.benchmarks.at("perception").at(0);
  ASSERT_EQ(section.charts.size(), 2u);
  EXPECT_EQ(section.charts[0].figure, "p50");
  EXPECT_TRUE(std::ranges::all_of(section.charts[0].bars, &detail::Bar::local));
  EXPECT_EQ(section.charts[1].figure, "max");
  EXPECT_NE(section.charts[1].axis.find("maximum latency"), std::string::npos);
  EXPECT_TRUE(std::ranges::any_of(section.charts[1].bars, [](const detail::Bar& b) {
    return !b.local && b.series == "Intel i7-12700H (RobotPerf)";
  }));
  const std::string svg = detail::bar_chart_svg(section.charts[1]);
  EXPECT_NE(svg.find("class=\"bar published\""), std::string::npos);
  EXPECT_NE(svg.find("fill=\"url(#hatch-a1-max)\""), std::string::npos);
  // The published maxima span boards and servers (over 50x): a logarithmic axis, said so; the
  // local p50s alone stay linear.
  EXPECT_NE(svg.find(">max latency (ms, log scale)<title>"), std::string::npos);
  EXPECT_EQ(detail::bar_chart_svg(section.charts[0]).find("log scale"), std::string::npos);
  // Published rows name no transport: the transport filter leaves them alone.
  for (const auto& bar : section.charts[1].bars) {
    EXPECT_EQ(bar.tags.contains("transport"), bar.local) << bar.series;
    EXPECT_EQ(bar.tags.at("source"), bar.local ? "local runs" : "published RobotPerf");
  }
  // The rows alike, by the summary's rule: black-box latency rows that pass the rules and state
  // 30 Hz (a row stating no rate may have been measured at any).
  std::size_t alike = 0;
  for (const auto& row : input.published.at(0).results) {
    alike += row.flags.empty() && row.metric == "latency" && row.type == "black" &&
             row.stated_rate() == "30 Hz";
  }
  ASSERT_GT(alike, 0u);
  const auto& vs = section.versus_published;
  ASSERT_EQ(vs.rows.size(), 1u);
  EXPECT_EQ(vs.rows[0][0], "AMD Ryzen 7 5800X · intra · 30 Hz");
  EXPECT_EQ(vs.rows[0][2], std::to_string(alike));
  EXPECT_TRUE(vs.rows[0][7].starts_with("lower than ")) << vs.rows[0][7];
}

// Eight series take the palette's eight colours; the ninth and after are drawn in outline, so no
// colour stands for two series; every bar's series is in the page's key.
TEST_F(Report, NoColourIsReusedAndEveryBarIsInTheKey) {
  int64_t t = 1'790'000'000'000'000'000;
  for (int k = 0; k < 10; ++k) {
    testing::SampleRun s;
    s.cpu = "CPU " + std::to_string(k);
    s.base_latency_ms = 3.0 + k;
    s.start_unix_ns = (t += 60'000'000'000);
    testing::write_sample(dir_, s);
  }
  const std::string html = render_html(load_report_inputs({dir_}), {});
  const std::regex entry("<li data-series=\"([^\"]+)\" data-colour=\"([^\"]+)\"");
  std::map<std::string, std::string> key;
  std::map<std::string, std::set<std::string>> series_of_colour;
  for (auto it = std::sregex_iterator(html.begin(), html.end(), entry);
       it != std::sregex_iterator(); ++it) {
    key[(*it)[1]] = (*it)[2];
    series_of_colour[(*it)[2]].insert((*it)[1]);
  }
  ASSERT_EQ(key.size(), 10u);
  for (const auto& [colour, series] : series_of_colour) {
    if (colour != "none") {
      EXPECT_EQ(series.size(), 1u) << colour << " is reused";
    }
  }
  EXPECT_EQ(series_of_colour["none"].size(), 2u);
  const std::regex bar("<g class=\"bar-row\" data-series=\"([^\"]+)\" data-colour=\"([^\"]+)\"");
  std::size_t bars = 0;
  for (auto it = std::sregex_iterator(html.begin(), html.end(), bar); it != std::sregex_iterator();
       ++it, ++bars) {
    ASSERT_TRUE(key.contains((*it)[1])) << (*it)[1] << " is not in the key";
    EXPECT_EQ(key[(*it)[1]], (*it)[2]) << (*it)[1] << " has another colour than its key's";
  }
  EXPECT_EQ(bars, 10u);
}

// Without --compare, the report compares two configurations that ran a benchmark in common, or
// says there are none; never two sides with nothing in common.
TEST_F(Report, TheAutomaticComparisonPicksConfigurationsWithABenchmarkInCommon) {
  int64_t t = 1'790'000'000'000'000'000;
  auto run = [&](const char* id, const char* cpu) {
    testing::SampleRun s;
    s.id = id;
    s.name = std::string(id) + "_bench";
    s.cpu = cpu;
    s.start_unix_ns = (t += 60'000'000'000);
    testing::write_sample(dir_, s);
  };
  run("a1", "First CPU");
  run("a2", "Second CPU");
  const detail::Model none = detail::build_model(load_report_inputs({dir_}), {});
  EXPECT_FALSE(none.comparison);
  EXPECT_NE(none.no_comparison.find("no two local configurations ran a benchmark in common"),
            std::string::npos);
  run("a2", "Third CPU");
  const detail::Model model = detail::build_model(load_report_inputs({dir_}), {});
  ASSERT_TRUE(model.comparison);
  EXPECT_EQ(model.comparison->a, "Second CPU · intra · 30 Hz");
  EXPECT_EQ(model.comparison->b, "Third CPU · intra · 30 Hz");
  EXPECT_FALSE(model.comparison->table.rows.empty());
}

// Radars only when asked, and never with more series than can be told apart.
TEST_F(Report, RadarsAreAnOptionWithAFewSeriesAtMost) {
  int64_t t = 1'790'000'000'000'000'000;
  for (const char* id : {"a1", "a2", "a3"}) {
    for (int k = 0; k < 9; ++k) {
      testing::SampleRun s;
      s.id = id;
      s.name = std::string(id) + "_bench";
      s.cpu = "CPU " + std::to_string(k);
      s.start_unix_ns = (t += 60'000'000'000);
      testing::write_sample(dir_, s);
    }
  }
  const auto input = load_report_inputs({dir_});
  EXPECT_EQ(count(render_html(input, {}), "<svg class=\"radar\""), 0u);
  ReportOptions options;
  options.radar = true;
  options.max_radar_series = 12;
  const detail::Model model = detail::build_model(input, options);
  for (const auto& radar : model.radars.at("perception")) {
    if (radar.axes.empty()) continue;
    EXPECT_EQ(radar.series.size(), kMaxRadarSeries) << radar.metric;
    EXPECT_EQ(radar.omitted.size(), 9u - kMaxRadarSeries) << radar.metric;
  }
  EXPECT_EQ(count(render_html(input, options), "<svg class=\"radar\""), 2u);
}

// A link that loops, named like a results file: one line, and the folder's other runs are read
// (listing and reporting a folder stopped at it).
TEST_F(Report, ALoopingLinkIsSkippedOneLine) {
  testing::write_sample(dir_, {});
  fs::create_symlink(dir_ / "loop.json", dir_ / "loop.json");
  const RunScan scan = scan_results(dir_);
  EXPECT_EQ(scan.runs.size(), 1u);
  ASSERT_EQ(scan.skipped.size(), 1u);
  EXPECT_NE(scan.skipped[0].find("loop.json: cannot be read"), std::string::npos)
      << scan.skipped[0];
  const auto input = load_report_inputs({dir_});
  EXPECT_EQ(input.runs.size(), 1u);
  EXPECT_EQ(input.skipped.size(), 1u);
}

// A field of another type than robotperf writes, wherever it is, skips that file with one line
// naming it; the folder's other runs are read, and what is read after loading (the machine
// table) shows what it cannot read as "-" instead of stopping the report.
TEST_F(Report, MalformedFilesAreSkippedOneLineEachAndTheReportRenders) {
  testing::write_sample(dir_, {});
  int64_t start = testing::SampleRun{}.start_unix_ns;
  auto variant = [&](const std::string& name, auto edit) {
    testing::SampleRun s;
    s.start_unix_ns = (start += 1'000'000'000);
    const auto written = testing::write_sample(dir_, s, false, 20);
    auto j = nlohmann::json::parse(read_text(written));
    edit(j);
    fs::remove(written);
    std::ofstream(dir_ / name) << j.dump();
  };
  variant("scale.json", [](auto& j) { j["latency_ms"]["from_scheduled_histogram"]["scale"] = 5; });
  variant("schema.json", [](auto& j) { j["schema"] = 1; });
  variant("available.json", [](auto& j) {
    j["power"]["total"].erase("sources");  // the power note then names the sources read
    j["power"]["sources"][0]["available"] = "yes";
  });
  variant("edges.json", [](auto& j) {
    j["latency_ms"]["from_scheduled_histogram"]["bins_per_decade"] = 1;
    j["latency_ms"]["from_scheduled_histogram"]["first_index"] = 20000;
  });
  variant("gpus.json", [](auto& j) {
    j["machine"]["gpus"] = nlohmann::json::array({"RTX 3060", nlohmann::json::array({7})});
    j["machine"]["cpu"]["frequency"]["governors"] = {1};
    j["machine"]["container"] = {{"detected", "no"}};
  });
  const RunScan scan = scan_results(dir_);
  EXPECT_EQ(scan.runs.size(), 2u);  // the valid one, and the one whose machine is unusual
  ASSERT_EQ(scan.skipped.size(), 4u);
  const std::vector<std::string> skipped_files = {"available.json", "edges.json", "scale.json",
                                                  "schema.json"};
  for (std::size_t i = 0; i < skipped_files.size(); ++i) {
    EXPECT_NE(scan.skipped[i].find(skipped_files[i] + ": "), std::string::npos) << scan.skipped[i];
    EXPECT_EQ(scan.skipped[i].find('\n'), std::string::npos) << scan.skipped[i];
  }
  EXPECT_NE(scan.skipped[0].find("power.sources[].available is \"yes\", expected true or false"),
            std::string::npos)
      << scan.skipped[0];
  const auto input = load_report_inputs({dir_});
  EXPECT_EQ(input.runs.size(), 2u);
  EXPECT_EQ(input.skipped.size(), 4u);
  const std::string md = render_markdown(input, {});
  EXPECT_NE(md.find("| RTX 3060, - |"), std::string::npos) << md.substr(md.find("## Machines"));
  EXPECT_NE(render_html(input, {}).find("skipped "), std::string::npos);
}

TEST_F(Report, ImpossibleFiguresMakeALocalRunInvalid) {
  const auto path = testing::write_sample(dir_, {});
  auto j = nlohmann::json::parse(read_text(path));
  j["latency_ms"]["from_scheduled"]["min"] = -0.5;
  j["counts"]["loss_percent"] = 250.0;
  std::ofstream(path) << j.dump();
  const StoredRun run = load_run(path);
  EXPECT_FALSE(run.valid);
  std::string reasons;
  for (const auto& r : run.invalid_reasons) reasons += r + "; ";
  EXPECT_NE(reasons.find("impossible figure: latency min -0.5 ms < 0"), std::string::npos)
      << reasons;
  EXPECT_NE(reasons.find("impossible figure: loss 250 % outside 0-100 %"), std::string::npos)
      << reasons;
  // Never plotted, so never in a median.
  EXPECT_NE(render_markdown(load_report_inputs({dir_}), {}).find("INVALID"), std::string::npos);
}

TEST_F(Report, BadInputsGiveOneClearLine) {
  write_two_machines(10, 11);
  std::ofstream(dir_ / "garbage.json") << "{not json";
  // Found by fuzz_results_json: a number beyond double's range is JSON's out_of_range, not a
  // parse error, and it escaped load_run.
  std::ofstream(dir_ / "huge.json")
      << R"({"schema": "robotperf.result/1", "x": 37.14e228590092565})";
  // The summaries --sweep and --repeat write beside their runs are not runs, and not bad input.
  std::ofstream(dir_ / "n3-x.sweep.json") << R"({"schema": "robotperf.sweep/1"})";
  std::ofstream(dir_ / "a1-x.series.json") << R"({"schema": "robotperf.series/1"})";
  const auto input = load_report_inputs({dir_});  // skipped inside a folder
  ASSERT_EQ(input.skipped.size(), 2u);
  EXPECT_NE(input.skipped[0].find("garbage.json"), std::string::npos);
  EXPECT_NE(input.skipped[1].find("huge.json: not valid JSON"), std::string::npos)
      << input.skipped[1];
  EXPECT_THROW(load_report_inputs({dir_ / "garbage.json"}), ReportError);  // named: an error
  EXPECT_THROW(load_report_inputs({dir_ / "missing"}), ReportError);
  ReportOptions options;
  options.compare = std::pair{"AMD Ryzen 7 5800X", "no such machine"};
  try {
    render_html(input, options);
    FAIL();
  } catch (const ReportError& e) {
    EXPECT_NE(std::string(e.what()).find("'no such machine' matches no"), std::string::npos);
  }
}

TEST_F(Report, ReadmeIsStableAndMatchesTheCommittedOnes) {
  const fs::path root = fs::path(ROBOTPERF_SOURCE_DIR) / "benchmarks/perception";
  for (const char* package : {"a1_perception_2nodes", "a2_rectify", "a3_stereo_image_proc",
                              "a4_depth_image_proc", "a5_resize"}) {
    const std::string first = render_package_readme(root / package);
    EXPECT_EQ(first, render_package_readme(root / package));
    EXPECT_EQ(first, read_text(root / package / "README.md"))
        << package << ": regenerate with robotperf readme";
  }
  // With results: tables per metric, flagged rows marked.
  fs::create_directories(dir_ / "pkg");
  fs::copy_file(published_a1(), dir_ / "pkg" / "benchmark.yaml");
  const std::string readme = render_package_readme(dir_ / "pkg");
  EXPECT_EQ(readme, render_package_readme(dir_ / "pkg"));
  EXPECT_NE(readme.find("### Latency"), std::string::npos);
  EXPECT_NE(readme.find("### Throughput"), std::string::npos);
  EXPECT_NE(readme.find("### Power"), std::string::npos);
  EXPECT_NE(readme.find("⚠ negative min latency"), std::string::npos);
  EXPECT_NE(readme.find("| Intel i7-12700H | workstation | black | 20.4 | ms | 07-07-2023 |"),
            std::string::npos);
}

}  // namespace
}  // namespace robotperf::report

// A GPU's load (NVML utilisation and memory, read with its power) is in the resources section.
TEST(Summary, ResourcesShowAGpusLoad) {
  using namespace robotperf;
  harness::RunResult r = report::testing::make_run({});
  r.resources.measured = true;
  r.resources.window_s = 3.0;
  metrics::SourceEnergy gpu;
  gpu.info.name = "nvml:gpu0";
  gpu.info.description = "NVIDIA H100 80GB HBM3";
  gpu.load = metrics::DeviceLoadSummary{30, 42.5, 97.0, 3ULL << 30, 80ULL << 30};
  r.power.sources.push_back(gpu);
  const std::string text = report::summary_table(r);
  EXPECT_NE(text.find("  nvml:gpu0 (NVIDIA H100 80GB HBM3): busy 42.5 % mean, 97.0 % max; "
                      "memory in use up to 3.00 of 80.00 GiB (30 readings)"),
            std::string::npos)
      << text;
}

// A device-resident run says so beside the backends, and records which topic stayed where.
TEST(Summary, DeviceResidentRunNamesWhatStayedOnTheDevice) {
  using namespace robotperf;
  harness::RunResult r = report::testing::make_run({});
  r.device_resident.push_back({"/rectify/image_rect", "rectify", {"resize"}, "cuda"});
  const std::string text = report::summary_table(r);
  EXPECT_NE(text.find("device-resident: /rectify/image_rect stays on the cuda device from rectify "
                      "to resize (no download, no upload: not the host-memory baseline)"),
            std::string::npos)
      << text;
  const sysinfo::MachineInfo machine = report::testing::make_machine({});
  const nlohmann::json j = report::result_to_json(r, machine);
  ASSERT_EQ(j["configuration"]["device_resident"].size(), 1u);
  EXPECT_EQ(j["configuration"]["device_resident"][0]["to"], nlohmann::json::array({"resize"}));
  const nlohmann::json baseline = report::result_to_json(report::testing::make_run({}), machine);
  EXPECT_TRUE(baseline["configuration"]["device_resident"].empty());
}

// The summary leads with what a reader takes away: p50 and p99 with their intervals, the
// throughput and its kind, then the verdict; RobotPerf's max comes later, named as a maximum.
TEST(Summary, LeadsWithTheMedianAndTheTailThenTheVerdict) {
  using namespace robotperf;
  const harness::RunResult r = report::testing::make_run({.messages = 400});
  const std::string text = report::summary_table(r);
  const auto lead = text.find("latency: p50 ");
  const auto throughput = text.find("throughput: 30.000 Hz out at 30.000 Hz offered (keeping up");
  const auto verdict = text.find("result: VALID\n");
  const auto table = text.find("latency (ms) ");
  const auto headline = text.find("RobotPerf headline (its latency is the maximum");
  ASSERT_NE(lead, std::string::npos) << text;
  EXPECT_EQ(text.find('\n') + 1, lead) << "the lead follows the configuration line\n" << text;
  EXPECT_LT(lead, throughput) << text;
  EXPECT_LT(throughput, verdict) << text;
  EXPECT_LT(verdict, table) << text;
  EXPECT_LT(table, headline) << text;
  // 400 samples bound both ends of the p99.
  const std::regex p99(R"(p99 [0-9.]+ ms \([0-9.]+ \.\. [0-9.]+\))");
  EXPECT_TRUE(std::regex_search(text.substr(lead, throughput - lead), p99)) << text;

  // Too few samples: the end they cannot give says how many would.
  const std::string few = report::summary_table(report::testing::make_run({.messages = 60}));
  EXPECT_NE(few.find(" .. ?: 368 samples give it) · 95 % intervals"), std::string::npos) << few;
}

// An invalid run says so in the lead with its reasons; wrong answers make the verdict INVALID
// even when the timing was valid.
TEST(Summary, TheVerdictCountsLossAndWrongAnswers) {
  using namespace robotperf;
  const std::string lossy = report::summary_table(report::testing::make_run({.lost = 3}));
  EXPECT_NE(lossy.find("result: INVALID — lost messages\n"), std::string::npos) << lossy;
  harness::RunResult wrong = report::testing::make_run({});
  wrong.functional.emplace();
  wrong.functional->valid = false;
  const std::string text = report::summary_table(wrong);
  EXPECT_NE(text.find("result: INVALID — wrong answers (functional check below)\n"),
            std::string::npos)
      << text;
}

// Warnings that hold for every run on this machine are one line of a few words; those about the
// run stay whole, a benchmark's `sample:` said beside a low count.
TEST(Summary, MachineConditionsAreOneLine) {
  using namespace robotperf;
  harness::RunResult r = report::testing::make_run(
      {.warnings = {{"virtual_machine", "running in a virtual machine: the hypervisor ..."},
                    {"container", "running in a container (docker): CPU and memory ..."},
                    {"system_busy", "system busy: other processes used 150 % of a core"},
                    {"samples", "60 measured messages: the p99's ..."}}});
  r.sample = "a goal, every 6 s";
  const std::string text = report::summary_table(r);
  EXPECT_NE(text.find("): virtual machine, container\n"), std::string::npos) << text;
  EXPECT_EQ(text.find("the hypervisor"), std::string::npos) << text;
  EXPECT_NE(text.find("warnings (this run):\n  system_busy: system busy: other processes used "
                      "150 % of a core\n  samples: 60 measured messages: the p99's ... (one "
                      "sample: a goal, every 6 s)\n"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("samples: 100 by the benchmark's nature: one is a goal, every 6 s\n"),
            std::string::npos)
      << text;
}

// The verdict ranks the run's max among the published platforms' black-box rows at its rate,
// each platform by its median; flagged rows, grey rows and other rates are left out.
TEST(Summary, TheVerdictRanksTheRunAgainstThePublishedPlatforms) {
  using namespace robotperf;
  harness::RunResult r = report::testing::make_run({.base_latency_ms = 5.0});
  const double max_ms = r.latency_from_scheduled.max / 1e6;  // about 10 ms
  report::PublishedBenchmark b;
  b.id = "a1";
  b.name = "a1_perception_2nodes";
  auto row = [&](std::string hardware, double ms, std::string type = "black", double hz = 30) {
    report::PublishedResult x;
    x.type = std::move(type);
    x.metric = "latency";
    x.metric_unit = "ms";
    x.hardware = std::move(hardware);
    x.value = ms;
    x.note_rate_hz = std::pair{hz, hz};
    return x;
  };
  b.results = {row("fast", 2.0),         row("slow", 40.0),
               row("slow", 60.0),        row("slower", max_ms * 3),
               row("grey", 1.0, "grey"), row("other rate", 1.0, "black", 60),
               row("flagged", 1.0)};
  b.results.back().flags.push_back("negative min latency");
  const std::string line = report::published_standing(r, {b});
  EXPECT_EQ(line.rfind("RobotPerf max " + report::format_fixed(max_ms, 3) +
                           " ms: lower than 2 of 3 published platforms (black-box, 30 Hz; best "
                           "2.000 ms, median " +
                           report::format_fixed(max_ms * 3, 3) + " ms)",
                       0),
            0u)
      << line;
  EXPECT_NE(report::summary_table(r, line).find("result: VALID · " + line + "\n"),
            std::string::npos);
  // Another benchmark's rows, or none at this rate: no standing rather than a wrong one.
  b.id = "a2";
  b.name = "a2_rectify";
  EXPECT_EQ(report::published_standing(r, {b}), "");
}

// A user's labels name series of their own; robotperf's automatic labels do not split them.
TEST(Series, UserLabelsNameSeriesTheAutomaticOnesDoNot) {
  using namespace robotperf::report;
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("robotperf-series-" + std::to_string(getpid()));
  fs::remove_all(dir);
  robotperf::report::testing::SampleRun s;
  s.labels = {{"rev", "pr42"}, {"robotperf.version", "0.1.0"}};
  const StoredRun run = load_run(robotperf::report::testing::write_sample(dir, s));
  EXPECT_EQ(run.labels.at("rev"), "pr42");
  const std::string series = detail::local_series(run);
  EXPECT_NE(series.find(" · rev=pr42"), std::string::npos) << series;
  EXPECT_EQ(series.find("robotperf.version"), std::string::npos) << series;
  fs::remove_all(dir);
}

// A user's label is a filter of its own on the page; robotperf's automatic labels are not.
TEST(Series, UserLabelsAreFiltersOfThePage) {
  using namespace robotperf::report;
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("robotperf-filter-" + std::to_string(getpid()));
  fs::remove_all(dir);
  for (const char* rev : {"main", "pr42"}) {
    robotperf::report::testing::SampleRun s;
    s.labels = {{"rev", rev}, {"robotperf.version", "0.1.0"}};
    s.start_unix_ns += rev[0] == 'm' ? 0 : 1'000'000'000;
    robotperf::report::testing::write_sample(dir, s);
  }
  const std::string html = render_html(load_report_inputs({dir}), {});
  EXPECT_NE(html.find("<legend>label-rev</legend>"), std::string::npos);
  EXPECT_NE(html.find("data-group=\"label-rev\" value=\"pr42\""), std::string::npos);
  EXPECT_NE(html.find("data-label-rev=\"main\""), std::string::npos);
  EXPECT_EQ(html.find("label-robotperf"), std::string::npos);
  fs::remove_all(dir);
}
