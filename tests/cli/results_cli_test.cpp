// The results workflow as a user runs it: run -> results list -> export/merge -> import -> report,
// and the report rendered by headless Chromium.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>

#include "../command_line.hpp"
#include "../report/sample_runs.hpp"
#include "../sanitized_build.hpp"
#include "../shared_data.hpp"
#include "robotperf/rmw/transport.hpp"

namespace {

namespace fs = std::filesystem;

// The published RobotPerf perception results.
fs::path published() {
  return shared_data("robotperf/perception");
}

using robotperf::test_support::Outcome;
using robotperf::test_support::robotperf_cli;
using robotperf::test_support::shell;

std::string read_text(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}

std::size_t count(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (std::size_t at = 0; (at = text.find(what, at)) != std::string::npos; at += what.size()) ++n;
  return n;
}

class ResultsCli : public ::testing::Test {
 protected:
  // Three short real runs, shared by the tests of this suite.
  static void SetUpTestSuite() {
    dir_ = fs::temp_directory_path() / ("robotperf-results-cli-" + std::to_string(getpid()));
    fs::remove_all(dir_);
    for (const char* args : {"run a5 --count 40 --csv", "run a5 --count 40", "run a2 --count 40"}) {
      const auto o =
          robotperf_cli(std::string(args) + " --quiet --output " + (dir_ / "results").string());
      ASSERT_EQ(o.exit_code, 0) << o.out;
    }
  }
  static void TearDownTestSuite() { fs::remove_all(dir_); }
  static fs::path dir_;
};
fs::path ResultsCli::dir_;

TEST_F(ResultsCli, ListShowsEveryRun) {
  const auto o = robotperf_cli("results list " + (dir_ / "results").string());
  ASSERT_EQ(o.exit_code, 0) << o.out;
  EXPECT_EQ(count(o.out, "a5-intra-"), 2u) << o.out;
  EXPECT_EQ(count(o.out, "a2-intra-"), 1u) << o.out;
  EXPECT_EQ(count(o.out, " valid\n"), 3u) << o.out;
  const auto missing = robotperf_cli("results list " + (dir_ / "nothing").string());
  EXPECT_EQ(missing.exit_code, 2);
  EXPECT_NE(missing.out.find("no such results folder"), std::string::npos);
}

// Published rows imported into a results folder are no runs: listed by no one, skipped silently.
TEST_F(ResultsCli, ListAsJsonAndCsvForPrograms) {
  const std::string folder = (dir_ / "results").string();
  const auto json_out = shell(std::string(ROBOTPERF_EXECUTABLE) + " results list " + folder +
                              " --format json 2>/dev/null");
  ASSERT_EQ(json_out.exit_code, 0) << json_out.out;
  const auto runs = nlohmann::json::parse(json_out.out);
  ASSERT_TRUE(runs.is_array());
  ASSERT_EQ(runs.size(), 3u);
  std::size_t a5 = 0;
  for (const auto& r : runs) {
    a5 += r.at("benchmark") == "a5";
    EXPECT_EQ(r.at("valid"), true);
    EXPECT_EQ(r.at("rmw"), "intra");
    EXPECT_EQ(r.at("rate_hz"), 30.0);
    EXPECT_GT(r.at("latency_max_ms").get<double>(), 0.0);
    EXPECT_TRUE(r.at("power_w").is_null() || r.at("power_w").get<double>() > 0);
  }
  EXPECT_EQ(a5, 2u);

  const auto csv = robotperf_cli("results list " + folder + " --format csv");
  ASSERT_EQ(csv.exit_code, 0) << csv.out;
  EXPECT_EQ(count(csv.out, "\r\n"), 4u) << csv.out;  // the header and three runs
  EXPECT_TRUE(csv.out.starts_with("file,benchmark,name,")) << csv.out;
  const std::string header = csv.out.substr(0, csv.out.find("\r\n"));
  const std::string first = csv.out.substr(
      header.size() + 2, csv.out.find("\r\n", header.size() + 2) - header.size() - 2);
  EXPECT_EQ(count(header, ","), count(first, ",")) << header << "\n" << first;

  ASSERT_EQ(
      robotperf_cli("results import " + (published() / "a5_resize").string() + " --into " + folder)
          .exit_code,
      0);
  const auto with_published = robotperf_cli("results list " + folder);
  EXPECT_EQ(with_published.out.find("skipped"), std::string::npos) << with_published.out;
  EXPECT_EQ(count(with_published.out, " valid\n"), 3u) << with_published.out;
  fs::remove(dir_ / "results" / "published-perception-a5_resize.json");
  EXPECT_EQ(robotperf_cli("results list " + folder + " --format xml").exit_code, 2);
}

TEST_F(ResultsCli, ExportToAFileOrStandardOutputAndMergeOnlyItsOwnBenchmark) {
  const std::string folder = (dir_ / "results").string();
  const auto dash =
      shell(std::string(ROBOTPERF_EXECUTABLE) + " results export -o - " + folder + " 2>/dev/null");
  ASSERT_EQ(dash.exit_code, 0) << dash.out;
  EXPECT_TRUE(dash.out.starts_with("results:\n")) << dash.out;
  const fs::path file = dir_ / "entries.yaml";
  const auto to_file = robotperf_cli("results export -o " + file.string() + " " + folder);
  ASSERT_EQ(to_file.exit_code, 0) << to_file.out;
  EXPECT_EQ(read_text(file), dash.out);

  const fs::path copy = dir_ / "a5-only" / "benchmark.yaml";
  fs::create_directories(copy.parent_path());
  fs::copy_file(published() / "a5_resize/benchmark.yaml", copy,
                fs::copy_options::overwrite_existing);
  const std::string before = read_text(copy);
  const auto refused = robotperf_cli("results export --merge " + copy.string() + " " + folder);
  EXPECT_EQ(refused.exit_code, 2) << refused.out;
  EXPECT_EQ(count(refused.out, "\n"), 1u) << refused.out;
  EXPECT_NE(refused.out.find("is a run of a2, not of a5"), std::string::npos) << refused.out;
  EXPECT_EQ(read_text(copy), before) << "nothing may be merged when a run is refused";
}

TEST_F(ResultsCli, CompareInTheTerminal) {
  const std::string inputs = "--results " + (dir_ / "results").string() + " --results " +
                             (published() / "a5_resize/benchmark.yaml").string();
  const auto o = robotperf_cli("compare a5-intra \"hardware=Intel i7-8700K,mode=black\" " + inputs);
  ASSERT_EQ(o.exit_code, 0) << o.out;
  EXPECT_NE(o.out.find("A = a5-intra"), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("B / A"), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("a5         latency max (ms)"), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("2 local runs, 0 published rows"), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("Significance:"), std::string::npos) << o.out;
  const auto unknown = robotperf_cli("compare a5-intra nowhere " + inputs);
  EXPECT_EQ(unknown.exit_code, 2);
  EXPECT_EQ(count(unknown.out, "\n"), 1u) << unknown.out;
  EXPECT_NE(unknown.out.find("'nowhere' matches no results file"), std::string::npos)
      << unknown.out;
}

TEST_F(ResultsCli, ExportMergeImportRoundTrip) {
  const auto yaml =
      robotperf_cli("results export --format benchmark-yaml " + (dir_ / "results").string());
  ASSERT_EQ(yaml.exit_code, 0) << yaml.out;
  EXPECT_EQ(yaml.out.rfind("results:\n", 0), 0u) << yaml.out;
  EXPECT_EQ(count(yaml.out, "metric: latency"), 3u);
  EXPECT_EQ(count(yaml.out, "metric: throughput"), 3u);

  // Merge into a copy of the published a5 file: existing bytes kept, new rows imported.
  const fs::path copy = dir_ / "a5" / "benchmark.yaml";
  fs::create_directories(copy.parent_path());
  fs::copy_file(published() / "a5_resize/benchmark.yaml", copy,
                fs::copy_options::overwrite_existing);
  const std::string before = read_text(copy);
  const auto merge = robotperf_cli("results export --merge " + copy.string() + " " +
                                   (dir_ / "results").string() + "/a5-intra-*.json");
  ASSERT_EQ(merge.exit_code, 0) << merge.out;
  EXPECT_NE(merge.out.find("added 4 result(s)"), std::string::npos) << merge.out;
  const std::string after = read_text(copy);
  EXPECT_GT(after.size(), before.size());
  const auto again = robotperf_cli("results export --merge " + copy.string() + " " +
                                   (dir_ / "results").string() + "/a5-intra-*.json");
  EXPECT_NE(again.out.find("added 0 result(s), 4 already there"), std::string::npos) << again.out;
  EXPECT_EQ(read_text(copy), after);

  const auto imported =
      robotperf_cli("results import " + copy.string() + " --into " + (dir_ / "imported").string());
  ASSERT_EQ(imported.exit_code, 0) << imported.out;
  EXPECT_NE(imported.out.find("a5_resize"), std::string::npos);
  EXPECT_NE(imported.out.find("rows that break the measurement rules"), std::string::npos);
  EXPECT_TRUE(fs::exists(dir_ / "imported" / "published-perception-a5_resize.json"));
}

TEST_F(ResultsCli, ImportFlagsThePublishedA1Rows) {
  const auto o = robotperf_cli("results import " + (published() / "a1_perception_2nodes").string());
  ASSERT_EQ(o.exit_code, 0) << o.out;
  EXPECT_NE(o.out.find("negative min latency"), std::string::npos);
  EXPECT_NE(o.out.find("is above 100 %"), std::string::npos);
  EXPECT_NE(o.out.find("W <= 0"), std::string::npos);
  const auto bad = robotperf_cli("results import " + (dir_ / "nope.yaml").string());
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_EQ(count(bad.out, "\n"), 1u) << bad.out;  // one line
}

// RobotPerf's b1-b3 rows ("not valid at the moment, just a placeholder") import, and a report
// draws them beside a local b3 run.
TEST_F(ResultsCli, PublishedLocalizationRowsPlotBesideALocalRun) {
  const fs::path localization = shared_data("robotperf/localization");
  auto o = robotperf_cli("results import " + localization.string());
  ASSERT_EQ(o.exit_code, 0) << o.out;
  for (const char* name : {"b1_visual_slam", "b2_map_localization", "b3_apriltag_detection"})
    EXPECT_NE(o.out.find(name), std::string::npos) << o.out;
  const fs::path out = dir_ / "b3";
  o = robotperf_cli("run b3 --count 110" + rate_option(20, 4) + " --quiet --output " +
                    out.string());
  ASSERT_EQ(o.exit_code, 0) << o.out;
  const fs::path html = dir_ / "b3.html";
  o = robotperf_cli("report " + out.string() + " " +
                    (localization / "b3_apriltag_detection" / "benchmark.yaml").string() +
                    " --html " + html.string());
  ASSERT_EQ(o.exit_code, 0) << o.out;
  const std::string page = read_text(html);
  // The published latency rows are bars beside the run's maximum, hatched.
  EXPECT_NE(page.find("data-series=\"Intel i7-12700H + NVIDIA GeForce RTX 3060 (ROBOTCORE® "
                      "Perception) (RobotPerf)\""),
            std::string::npos);
  EXPECT_NE(page.find("class=\"bar published\""), std::string::npos);
  EXPECT_NE(page.find("b3-intra-"), std::string::npos);
}

TEST_F(ResultsCli, ReportNeedsAnOutputAndExistingInputs) {
  EXPECT_EQ(robotperf_cli("report " + (dir_ / "results").string()).exit_code, 2);
  const auto o = robotperf_cli("report " + (dir_ / "missing").string() + " --html x.html");
  EXPECT_EQ(o.exit_code, 2);
  EXPECT_NE(o.out.find("no such file or folder"), std::string::npos) << o.out;
}

// `--md -` is standard output, and a device path (/dev/stdout, a pipe) is written through: the
// report alone on stdout, no file named "-", no link replaced.
TEST_F(ResultsCli, ReportGoesToStandardOutputOrThroughADevice) {
  const std::string inputs = (dir_ / "results").string() + " " + published().string();
  const auto dash = shell(std::string("{ ") + ROBOTPERF_EXECUTABLE + " report " + inputs +
                          " --md - 2>/dev/null; }");
  ASSERT_EQ(dash.exit_code, 0) << dash.out;
  EXPECT_TRUE(dash.out.starts_with("# ")) << dash.out.substr(0, 200);
  EXPECT_EQ(dash.out.find("report: "), std::string::npos) << "stdout is the report alone";
  const auto device = shell("cd " + dir_.string() + " && " + ROBOTPERF_EXECUTABLE + " report " +
                            inputs + " --md - > /dev/null && " + ROBOTPERF_EXECUTABLE + " report " +
                            inputs + " --md /dev/stdout | head -c 2");
  EXPECT_FALSE(fs::exists(dir_ / "-"));
  EXPECT_EQ(device.out.substr(0, 2), "# ") << device.out;
  EXPECT_TRUE(fs::is_symlink(fs::symlink_status("/dev/stdout"))) << "/dev/stdout was replaced";
  EXPECT_EQ(robotperf_cli("report " + inputs + " --md - --html -").exit_code, 2);
}

TEST_F(ResultsCli, ReportRendersInHeadlessChromium) {
  const auto which = shell("command -v chromium");
  ASSERT_EQ(which.exit_code, 0) << "chromium is not installed: run scripts/install-deps.sh";
  const fs::path html = dir_ / "report.html";
  const auto o =
      robotperf_cli("report " + (dir_ / "results").string() + " " + published().string() +
                    " --html " + html.string() + " --md " + (dir_ / "report.md").string());
  ASSERT_EQ(o.exit_code, 0) << o.out;

  const std::string chromium =
      "chromium --headless --no-sandbox --disable-gpu --disable-quic --no-first-run "
      "--disable-background-networking --disable-component-update --disable-sync "
      "--hide-scrollbars --user-data-dir=" +
      (dir_ / "chromium-profile").string();
  // The DOM as the browser parsed it: the summary, the plots and the tables are there; radars only
  // when asked.
  const auto dom = shell(chromium + " --dump-dom file://" + html.string() + " 2>/dev/null");
  ASSERT_EQ(dom.exit_code, 0) << dom.out;
  EXPECT_NE(dom.out.find("<section class=\"summary\""), std::string::npos);
  EXPECT_NE(dom.out.find("<table class=\"at-a-glance\""), std::string::npos);
  EXPECT_EQ(count(dom.out, "<svg class=\"radar\""), 0u);
  EXPECT_EQ(count(dom.out, "data-figure=\"p50\""), 2u);  // a2 and a5 ran here
  EXPECT_GE(count(dom.out, "data-figure=\"max\""), 4u);  // beside the published rows
  EXPECT_EQ(count(dom.out, "<svg class=\"cdf\""), 2u);   // a2 and a5
  EXPECT_GE(count(dom.out, "<table class=\"runs\""), 2u);
  EXPECT_GE(count(dom.out, "<table class=\"published\""), 4u);
  EXPECT_NE(dom.out.find("<table class=\"machines\""), std::string::npos);

  // The screenshot: the radar plots and tables are drawn.
  const fs::path png = dir_ / "report.png";
  const auto shot = shell(chromium + " --window-size=1600,1400 --screenshot=" + png.string() +
                          " file://" + html.string());
  ASSERT_EQ(shot.exit_code, 0) << shot.out;
  EXPECT_EQ(shot.out.find("Uncaught"), std::string::npos) << shot.out;
  const cv::Mat image = cv::imread(png.string(), cv::IMREAD_COLOR);
  ASSERT_FALSE(image.empty()) << "no screenshot at " << png;
  EXPECT_EQ(image.cols, 1600);
  EXPECT_EQ(image.rows, 1400);
  // The first series' colour (#0072b2, the first local configuration) is drawn, the table
  // header colour (#eef3f8) too, and the page is not blank.
  std::size_t series = 0, header = 0, ink = 0;
  for (int y = 0; y < image.rows; ++y) {
    for (int x = 0; x < image.cols; ++x) {
      const cv::Vec3b p = image.at<cv::Vec3b>(y, x);  // BGR
      auto near = [&](int r, int g, int b) {
        return std::abs(p[2] - r) < 12 && std::abs(p[1] - g) < 12 && std::abs(p[0] - b) < 12;
      };
      series += near(0x00, 0x72, 0xb2);
      header += near(0xee, 0xf3, 0xf8);
      ink += p[0] < 128 && p[1] < 128 && p[2] < 128;
    }
  }
  EXPECT_GT(series, 100u);
  EXPECT_GT(header, 1000u);
  EXPECT_GT(ink, 5000u);
}

// Run in the page by Chromium, with the page as loaded, with a transport filtered out, and with it
// back: every text of every plot lies inside its plot and overlaps no other text of it; every bar's
// series and every valid latency curve's is in the page's key, drawn in its key's colour (a
// published bar without a colour is hatched, named beside it and said so in the key), and no
// colour stands for two series;
// the filter hides exactly the rows and bars of that transport and shows them again. The result
// is written into the DOM, which --dump-dom prints.
constexpr const char* kLayoutCheck = R"(<script>
window.addEventListener('load', () => {
  const problems = [];
  let texts = 0;
  const shown = e => e.getBoundingClientRect().height > 0;
  function layout(when) {
    document.querySelectorAll('svg').forEach((svg, i) => {
      if (!shown(svg)) return;
      const box = svg.getBoundingClientRect();
      const plot = when + ': ' + (svg.getAttribute('class') || 'svg') + ' ' + i + ' ' +
                   (svg.dataset.category || svg.dataset.benchmark || '') + ' ' +
                   (svg.dataset.metric || svg.dataset.figure || '');
      const placed = [];
      svg.querySelectorAll('text').forEach(t => {
        const r = t.getBoundingClientRect();
        if (r.width === 0) return;
        ++texts;
        const label = t.childNodes[0] ? t.childNodes[0].textContent : t.textContent;
        if (r.left < box.left - 1 || r.right > box.right + 1 || r.top < box.top - 1 ||
            r.bottom > box.bottom + 1)
          problems.push('clipped in ' + plot + ': ' + label);
        for (const [o, other] of placed) {
          const w = Math.min(r.right, o.right) - Math.max(r.left, o.left);
          const h = Math.min(r.bottom, o.bottom) - Math.max(r.top, o.top);
          if (w > 1 && h > 2) problems.push('overlap in ' + plot + ': ' + label + ' / ' + other);
        }
        placed.push([r, label]);
      });
    });
  }
  layout('as loaded');

  const key = new Map();
  const seriesOfColour = new Map();
  const note = (colour, series) => {
    if (colour === 'none') return;
    if (!seriesOfColour.has(colour)) seriesOfColour.set(colour, new Set());
    seriesOfColour.get(colour).add(series);
  };
  document.querySelectorAll('#series-key li[data-series]').forEach(li => {
    key.set(li.dataset.series, li.dataset.colour);
    note(li.dataset.colour, li.dataset.series);
    if (!shown(li)) problems.push('key entry not visible: ' + li.dataset.series);
  });
  const bars = document.querySelectorAll('g.bar-row');
  bars.forEach(g => {
    // A published bar without a colour is hatched and named beside it; any other is in the key.
    const named = g.dataset.colour === 'none' && g.dataset.source === 'published RobotPerf';
    if (named) {
      if (!document.querySelector('#series-key li.published-key'))
        problems.push('no key entry for the hatched published bars');
    } else if (!key.has(g.dataset.series)) problems.push('not in the key: ' + g.dataset.series);
    else if (key.get(g.dataset.series) !== g.dataset.colour)
      problems.push('colour unlike its key: ' + g.dataset.series);
    note(g.dataset.colour, g.dataset.series);
    const rect = g.querySelector('rect.bar');
    if (rect.classList.contains('local') && g.dataset.colour !== 'none' &&
        rect.getAttribute('fill') !== g.dataset.colour)
      problems.push('bar drawn in another colour: ' + g.dataset.series);
  });
  // The latency curves are drawn in their configuration's colour, INVALID runs' in grey.
  document.querySelectorAll('polyline.curve:not(.invalid)').forEach(curve => {
    const series = curve.dataset.series;
    if (!key.has(series)) problems.push('curve not in the key: ' + series);
    else if (key.get(series) !== 'none' && key.get(series) !== curve.getAttribute('stroke'))
      problems.push('curve in another colour than its key: ' + series);
    note(curve.getAttribute('stroke'), series);
  });
  seriesOfColour.forEach((series, colour) => {
    if (series.size > 1) problems.push(colour + ' stands for ' + Array.from(series).join(' and '));
  });

  const box = document.querySelector('#filters input[data-group="transport"][value="fastdds"]');
  const tagged = Array.from(document.querySelectorAll('[data-transport]'))
                     .filter(e => !e.closest('details:not([open])'));
  const fastdds = tagged.filter(e => e.dataset.transport === 'fastdds');
  const others = tagged.filter(e => e.dataset.transport !== 'fastdds');
  if (!box) problems.push('no fastdds filter');
  if (fastdds.length < 2 || others.length < 2) problems.push('too few tagged rows to filter');
  if (box && fastdds.every(shown) && others.every(shown)) {
    box.checked = false;
    box.dispatchEvent(new Event('change'));
    fastdds.filter(shown).forEach(e => problems.push('filtered but shown: ' + e.outerHTML.slice(0, 80)));
    others.filter(e => !shown(e)).forEach(e => problems.push('hidden by another filter: ' + e.outerHTML.slice(0, 80)));
    layout('fastdds filtered out');
    box.checked = true;
    box.dispatchEvent(new Event('change'));
    fastdds.filter(e => !shown(e)).forEach(e => problems.push('not shown again: ' + e.outerHTML.slice(0, 80)));
    layout('fastdds back');
  } else if (box) {
    problems.push('rows hidden before any filter');
  }
  const out = document.createElement('pre');
  out.id = 'layout-check';
  out.textContent = (problems.length ? 'PROBLEMS\n' + problems.join('\n') : 'OK') + '\n' +
                    bars.length + ' bars\n' + texts + ' texts';
  document.body.appendChild(out);
});
</script>)";

// A folder as a user has it after a while: two transports, both process layouts, two rates, an
// INVALID run and published rows of two categories.
TEST_F(ResultsCli, MixedReportLabelsNeitherOverlapNorClipInChromium) {
  ASSERT_EQ(shell("command -v chromium").exit_code, 0)
      << "chromium is not installed: run scripts/install-deps.sh";
  const fs::path mixed = dir_ / "mixed";
  // The DDS runs on a domain no other process uses.
  const std::string dds = " --domain " + std::to_string(robotperf::rmw::reserved_domain());
  const std::string own_rate = sanitized_rate_option(5);
  for (const std::string& args :
       {"run a5 --count 40" + own_rate, "run a5 --count 40 --rmw fastdds" + own_rate + dds,
        "run a5 --count 40" + rate_option(60, 10),
        "run a1 --count 40 --processes per-node" + own_rate + dds, "run a1 --count 40" + own_rate,
        "run a2 --count 40" + own_rate, "run a5 --count 8" + own_rate}) {
    const auto o = robotperf_cli(args + " --quiet --output " + mixed.string());
    ASSERT_TRUE(o.exit_code == 0 || (o.exit_code == 3 && args.starts_with("run a5 --count 8")))
        << args << ": " << o.out;
  }
  const fs::path shared = shared_data("robotperf");
  ASSERT_EQ(robotperf_cli("results import " + (shared / "perception").string() + " " +
                          (shared / "control").string() + " --into " + mixed.string())
                .exit_code,
            0);
  // A configuration's history of 12 runs, slower from the 8th: its trend and change point.
  for (int i = 0; i < 12; ++i) {
    robotperf::report::testing::SampleRun s;
    s.base_latency_ms = i < 7 ? 4.0 + 0.05 * (i % 3) : 5.0 + 0.05 * (i % 3);
    s.start_unix_ns += i * 3'600'000'000'000LL;
    robotperf::report::testing::write_sample(mixed, s);
  }
  const fs::path html = dir_ / "mixed.html";
  const auto o = robotperf_cli("report " + mixed.string() + " --html " + html.string());
  ASSERT_EQ(o.exit_code, 0) << o.out;
  std::string page = read_text(html);
  EXPECT_NE(page.find("1 INVALID run"), std::string::npos);
  EXPECT_NE(page.find("class=\"curve invalid\""), std::string::npos);
  EXPECT_EQ(count(page, "<svg class=\"trend\""), 1u);
  EXPECT_EQ(count(page, "<g class=\"change-point\""), 1u);
  EXPECT_NE(page.find("From run 8 ("), std::string::npos);
  const auto body_end = page.rfind("</body>");
  ASSERT_NE(body_end, std::string::npos);
  page.insert(body_end, kLayoutCheck);
  const fs::path checked = dir_ / "mixed-checked.html";
  {
    std::ofstream out(checked, std::ios::binary);
    out << page;
  }
  const auto dom = shell(
      "timeout 120 chromium --headless --no-sandbox --disable-gpu --disable-quic --no-first-run "
      "--disable-background-networking --disable-component-update --disable-sync "
      "--hide-scrollbars --window-size=1600,1400 --user-data-dir=" +
      (dir_ / "chromium-layout").string() + " --dump-dom file://" + checked.string() +
      " 2>/dev/null");
  ASSERT_EQ(dom.exit_code, 0) << dom.out.substr(0, 400);
  const auto at = dom.out.find("<pre id=\"layout-check\">");
  ASSERT_NE(at, std::string::npos) << "the check did not run";
  const std::string result = dom.out.substr(at, dom.out.find("</pre>", at) - at);
  EXPECT_NE(result.find(">OK\n"), std::string::npos) << result;
  // The plots were there to check: bars of two categories, distributions, legends.
  const auto texts = std::stoul(result.substr(result.rfind('\n') + 1));
  EXPECT_GT(texts, 150u) << result;
  const auto bars_at = result.rfind(" bars\n");
  ASSERT_NE(bars_at, std::string::npos) << result;
  EXPECT_GT(std::stoul(result.substr(result.rfind('\n', bars_at - 1) + 1)), 20u) << result;
}

TEST_F(ResultsCli, RunWritesItsReport) {
  const fs::path out = dir_ / "with-report";
  const auto o = robotperf_cli("run a5 --count 40 --quiet --report --output " + out.string());
  ASSERT_EQ(o.exit_code, 0) << o.out;
  std::size_t reports = 0;
  for (const auto& e : fs::directory_iterator(out)) {
    if (e.path().string().ends_with(".report.html")) {
      ++reports;
      const std::string html = read_text(e.path());
      // One benchmark, one run, no published rows: its p50 alone, and nothing to filter.
      EXPECT_EQ(count(html, "<svg class=\"barchart\""), 1u);
      EXPECT_EQ(html.find("<script"), std::string::npos);
      EXPECT_NE(html.find("<table class=\"runs\""), std::string::npos);
    }
  }
  EXPECT_EQ(reports, 1u);
}

TEST_F(ResultsCli, ReadmeCheckSaysWhenOutOfDate) {
  const fs::path root = dir_ / "benchmarks";
  const fs::path package = root / "perception/x5_resize";
  fs::create_directories(root / "perception");
  fs::copy(fs::path(ROBOTPERF_SOURCE_DIR) / "benchmarks/perception/a5_resize", package,
           fs::copy_options::recursive);
  // Benchmark folders add to the built-in ones: the copy needs an id of its own.
  std::ifstream meta_in(package / "benchmark.yaml");
  std::string meta((std::istreambuf_iterator<char>(meta_in)), std::istreambuf_iterator<char>());
  meta_in.close();
  meta.replace(meta.find("id: a5"), 6, "id: x5");
  std::ofstream(package / "benchmark.yaml") << meta;
  const std::string benchmarks = "--benchmarks " + root.string();
  EXPECT_EQ(robotperf_cli(benchmarks + " readme x5").exit_code, 0);
  EXPECT_EQ(robotperf_cli(benchmarks + " readme x5 --check").exit_code, 0);
  std::ofstream(package / "README.md", std::ios::app) << "edited\n";
  const auto stale = robotperf_cli(benchmarks + " readme x5 --check");
  EXPECT_EQ(stale.exit_code, 1);
  EXPECT_NE(stale.out.find("out of date"), std::string::npos);
  EXPECT_EQ(robotperf_cli(benchmarks + " readme x5").exit_code, 0);
  EXPECT_EQ(robotperf_cli(benchmarks + " readme x5 --check").exit_code, 0);
}

}  // namespace
