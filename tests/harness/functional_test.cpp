// Functional accuracy: the a3, a4, a6 and a7 benchmarks meet their stated accuracy, a broken graph
// is reported functionally invalid, and inputs that cannot be paired are dropped, never mixed.
#include "robotperf/harness/functional.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <regex>

#include "robotperf/harness/run.hpp"
#include "robotperf/msgs/sensor_msgs.hpp"
#include "robotperf/rmw/transport.hpp"
#include "test_package.hpp"

namespace robotperf::harness {
namespace {

namespace fs = std::filesystem;

const fs::path kBenchmarks = fs::path(ROBOTPERF_SOURCE_DIR) / "benchmarks" / "perception";

std::string read(const fs::path& p) {
  std::ifstream in(p);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// A copy of a shipped package, with `edit` applied to its graph.yaml.
class PackageCopy {
 public:
  PackageCopy(const std::string& package, const std::string& id,
              const std::function<std::string(std::string)>& edit) {
    root_ =
        fs::temp_directory_path() / ("robotperf-functional-" + std::to_string(getpid()) + "-" + id);
    dir_ = root_ / "perception" / (id + "_copy");
    fs::create_directories(dir_);
    std::string meta = read(kBenchmarks / package / "benchmark.yaml");
    meta = std::regex_replace(meta, std::regex("^id: .*$", std::regex::multiline), "id: " + id);
    meta = std::regex_replace(meta, std::regex("^name: .*$", std::regex::multiline),
                              "name: " + id + "_copy");
    std::ofstream(dir_ / "benchmark.yaml") << meta;
    std::ofstream(dir_ / "graph.yaml") << edit(read(kBenchmarks / package / "graph.yaml"));
  }
  ~PackageCopy() { fs::remove_all(root_); }
  BenchmarkSpec spec() const { return load_benchmark(dir_); }

 private:
  fs::path root_, dir_;
};

std::string replace_all(std::string s, const std::string& from, const std::string& to) {
  for (std::size_t at = s.find(from); at != std::string::npos; at = s.find(from, at + to.size())) {
    s.replace(at, from.size(), to);
  }
  return s;
}

RunOptions quick(std::size_t count, double rate_hz, const std::string& rmw = "intra") {
  RunOptions o;
  o.load.count = count;
  o.load.rate_hz = rate_hz;
  o.load.warmup = 2;
  o.transport.rmw = rmw;
  o.transport.domain_id = rmw::reserved_domain();
  return o;
}

std::string reasons(const FunctionalResult& f) {
  std::string out;
  for (const auto& r : f.reasons) out += r + "; ";
  return out;
}

const FunctionalMetric& metric(const FunctionalResult& f, const std::string& name) {
  for (const auto& m : f.metrics) {
    if (m.name == name) return m;
  }
  throw std::runtime_error("no metric " + name);
}

TEST(Functional, A3StereoMeetsItsStatedAccuracy) {
  const BenchmarkSpec spec = load_benchmark(kBenchmarks / "a3_stereo_image_proc");
  ASSERT_TRUE(spec.functional);
  EXPECT_EQ(spec.functional->evaluator, "stereo_disparity");
  EXPECT_EQ(spec.functional->thresholds.at("bad1").max, 0.05);
  const RunResult r = run_benchmark(spec, quick(14, 10));
  EXPECT_EQ(r.matched, 12u);
  ASSERT_TRUE(r.functional);
  const FunctionalResult& f = *r.functional;
  EXPECT_TRUE(f.valid) << reasons(f);
  EXPECT_EQ(f.requested, 12u);  // sample 16 > measured: every measured output
  EXPECT_EQ(f.evaluated, 12u);
  EXPECT_GT(metric(f, "valid_fraction").value, 0.85);
  EXPECT_LT(metric(f, "bad1").value, 0.05);
  EXPECT_LT(metric(f, "mae_px").value, 0.5);
  ASSERT_EQ(r.nodes.size(), 1u);
  EXPECT_EQ(r.nodes[0].counters.at("sets_processed"), 14u);
  EXPECT_EQ(r.nodes[0].counters.at("unpaired_left_image"), 0u);
}

TEST(Functional, SwappedLeftAndRightIsFunctionallyInvalid) {
  const PackageCopy swapped("a3_stereo_image_proc", "x3", [](std::string g) {
    g = replace_all(g, "left_image: /left/image_rect", "left_image: /TMP");
    g = replace_all(g, "right_image: /right/image_rect", "right_image: /left/image_rect");
    return replace_all(g, "left_image: /TMP", "left_image: /right/image_rect");
  });
  const RunResult r = run_benchmark(swapped.spec(), quick(8, 10));
  EXPECT_EQ(r.lost, 0u);  // the measurement itself is fine ...
  ASSERT_TRUE(r.functional);
  EXPECT_FALSE(r.functional->valid);  // ... but the answer is wrong
  EXPECT_FALSE(metric(*r.functional, "valid_fraction").passed);
  ASSERT_FALSE(r.functional->reasons.empty());
  EXPECT_NE(reasons(*r.functional).find("valid_fraction"), std::string::npos);
}

// A matcher that searches fewer disparities than the scene holds misses the nearer pixels: they
// count against its valid_fraction, not left out because the output says it did not look.
TEST(Functional, NarrowSearchRangeCountsTheDisparitiesItMisses) {
  const PackageCopy narrow("a3_stereo_image_proc", "x3", [](std::string g) {
    return replace_all(g, "disparity_range: 64", "disparity_range: 16");
  });
  const RunResult r = run_benchmark(narrow.spec(), quick(6, 10));
  ASSERT_TRUE(r.functional);
  EXPECT_FALSE(metric(*r.functional, "valid_fraction").passed);
  EXPECT_FALSE(r.functional->valid);
}

TEST(Functional, A4PointCloudMeetsItsAccuracyFromMetresAndMillimetres) {
  const BenchmarkSpec spec = load_benchmark(kBenchmarks / "a4_depth_image_proc");
  const RunResult metres = run_benchmark(spec, quick(10, 15));
  ASSERT_TRUE(metres.functional);
  EXPECT_TRUE(metres.functional->valid) << reasons(*metres.functional);
  EXPECT_LT(metric(*metres.functional, "max_error_m").value, 1e-5);
  EXPECT_EQ(metric(*metres.functional, "valid_fraction").value, 1.0);
  EXPECT_EQ(metric(*metres.functional, "colour_match").value, 1.0);

  const PackageCopy mm("a4_depth_image_proc", "x4", [](std::string g) {
    return replace_all(g, "stream: depth}", "stream: depth_mm}");
  });
  const RunResult millimetres = run_benchmark(mm.spec(), quick(10, 15));
  ASSERT_TRUE(millimetres.functional);
  EXPECT_TRUE(millimetres.functional->valid) << reasons(*millimetres.functional);
  const double mean = metric(*millimetres.functional, "mean_error_m").value;
  EXPECT_GT(mean, 1e-5);  // millimetre rounding shows ...
  EXPECT_LT(mean, 5e-4);  // ... but stays within half a millimetre on average
}

TEST(Functional, UnpairedInputsAreDroppedAndCountedNotMixed) {
  // The depth images pass through a relay that drops every third one: those frames' colour
  // images and CameraInfos must be dropped by the pairing, never combined with another frame's
  // depth (the colour check would see it: the boxes move between frames).
  const PackageCopy lossy("a4_depth_image_proc", "x5", [](std::string g) {
    g = replace_all(g, "depth: /camera/depth_registered/image_rect",
                    "depth: /camera/depth_registered/image_rect_lossy");
    g = replace_all(g, "max_loss_percent: 0.0", "max_loss_percent: 50.0");
    return replace_all(g, "\nfunctional:",
                       "\n  - name: lossy\n"
                       "    kernel: util/relay\n"
                       "    parameters: {drop_every: 3}\n"
                       "    topics: {input: /camera/depth_registered/image_rect,"
                       " output: /camera/depth_registered/image_rect_lossy}\n"
                       "functional:");
  });
  const BenchmarkSpec spec = lossy.spec();
  ASSERT_EQ(spec.nodes.size(), 2u);
  const RunResult r = run_benchmark(spec, quick(12, 15));
  EXPECT_EQ(r.sent, 12u);
  // The relay drops its 3rd, 6th, ... message: ids 2, 5, 8, 11, all measured (warm-up 2).
  EXPECT_EQ(r.measured, 10u);
  EXPECT_EQ(r.matched, 6u);
  const auto& counters = r.nodes[0].counters;
  EXPECT_EQ(counters.at("sets_processed"), 8u);
  EXPECT_EQ(counters.at("unpaired_depth"), 0u);
  // The last lost frame's colour may still wait for a partner when the run ends.
  EXPECT_GE(counters.at("unpaired_image"), 3u);
  EXPECT_GE(counters.at("unpaired_camera_info"), 3u);
  ASSERT_TRUE(r.functional);
  EXPECT_TRUE(r.functional->valid) << reasons(*r.functional);
  EXPECT_EQ(metric(*r.functional, "colour_match").value, 1.0);
}

TEST(Functional, PointCloudEvaluatorCatchesWrongPoints) {
  const Dataset dataset = load_dataset("perception/depth");
  const BenchmarkSpec spec = load_benchmark(kBenchmarks / "a4_depth_image_proc");
  const auto& depth = dataset.stream("depth");
  const auto& image = dataset.stream("image");
  const auto& info = dataset.stream("camera_info");
  // A cloud whose z is 1 cm too far: a kernel with a wrong depth scale or offset.
  msgs::PointCloud2 cloud;
  {
    const auto& d = *static_cast<const msgs::Image*>(depth.messages[3].get());
    const auto& c = *static_cast<const msgs::Image*>(image.messages[3].get());
    const auto& ci = *static_cast<const msgs::CameraInfo*>(info.messages[3].get());
    cloud.header = d.header;
    cloud.width = d.width;
    cloud.height = d.height;
    cloud.point_step = 32;
    cloud.row_step = 32 * d.width;
    cloud.fields = {{"x", 0, 7, 1}, {"y", 4, 7, 1}, {"z", 8, 7, 1}, {"rgb", 16, 7, 1}};
    cloud.data.assign(cloud.row_step * d.height, 0);
    for (uint32_t v = 0; v < d.height; ++v) {
      for (uint32_t u = 0; u < d.width; ++u) {
        float z;
        std::memcpy(&z, d.data.data() + v * d.step + 4 * u, 4);
        z += 0.01f;
        const float xyz[3] = {static_cast<float>((u - ci.p[2]) * z / ci.p[0]),
                              static_cast<float>((v - ci.p[6]) * z / ci.p[5]), z};
        uint8_t* p = cloud.data.data() + v * cloud.row_step + u * 32;
        std::memcpy(p, xyz, 12);
        const uint8_t* px = c.data.data() + v * c.step + 3 * u;
        p[16] = px[2];
        p[17] = px[1];
        p[18] = px[0];
      }
    }
  }
  const auto message = std::make_shared<const msgs::PointCloud2>(std::move(cloud));
  const FunctionalResult f = evaluate_functional(*spec.functional, dataset, {{3, message}}, 1);
  EXPECT_FALSE(f.valid);
  EXPECT_NEAR(metric(f, "mean_error_m").value, 0.01, 0.002);
  EXPECT_NE(reasons(f).find("mean_error_m"), std::string::npos) << reasons(f);

  const FunctionalResult none = evaluate_functional(*spec.functional, dataset, {}, 4);
  EXPECT_FALSE(none.valid);
  EXPECT_NE(none.reasons[0].find("no output could be evaluated"), std::string::npos);
}

TEST(Functional, A6ScanMeetsItsAccuracyFromMetresAndMillimetres) {
  const BenchmarkSpec spec = load_benchmark(kBenchmarks / "a6_depthimage_to_laserscan");
  const RunResult metres = run_benchmark(spec, quick(10, 15));
  ASSERT_TRUE(metres.functional);
  EXPECT_TRUE(metres.functional->valid) << reasons(*metres.functional);
  EXPECT_LT(metric(*metres.functional, "max_error_m").value, 1e-5);
  EXPECT_EQ(metric(*metres.functional, "valid_fraction").value, 1.0);

  const PackageCopy mm("a6_depthimage_to_laserscan", "x6", [](std::string g) {
    return replace_all(g, "stream: depth}", "stream: depth_mm}");
  });
  const RunResult millimetres = run_benchmark(mm.spec(), quick(10, 15));
  ASSERT_TRUE(millimetres.functional);
  EXPECT_TRUE(millimetres.functional->valid) << reasons(*millimetres.functional);
  EXPECT_GT(metric(*millimetres.functional, "mean_error_m").value, 1e-5);
}

TEST(Functional, A7ScanMeetsItsAccuracy) {
  const RunResult r =
      run_benchmark(load_benchmark(kBenchmarks / "a7_pointcloud_to_laserscan"), quick(10, 15));
  ASSERT_TRUE(r.functional);
  EXPECT_TRUE(r.functional->valid) << reasons(*r.functional);
  EXPECT_LT(metric(*r.functional, "max_error_m").value, 1e-5);
  EXPECT_EQ(metric(*r.functional, "valid_fraction").value, 1.0);
  // A slab that the evaluator is told differs from the node's: the floor's points, 1.2 m down,
  // are in the truth but not in the scan.
  const PackageCopy lower("a7_pointcloud_to_laserscan", "x7", [](std::string g) {
    return replace_all(g, "{min_height: -1.1,", "{min_height: -1.3,");
  });
  const RunResult floor = run_benchmark(lower.spec(), quick(10, 15));
  ASSERT_TRUE(floor.functional);
  EXPECT_FALSE(floor.functional->valid);
  EXPECT_GT(metric(*floor.functional, "max_error_m").value, 0.1);
}

// Scans that are wrong in two ways: every beam 1 m (a kernel that ignores the depth), and no beam
// at all (one that drops every range).
TEST(Functional, ScanEvaluatorCatchesWrongRanges) {
  const Dataset dataset = load_dataset("perception/depth");
  const BenchmarkSpec spec = load_benchmark(kBenchmarks / "a6_depthimage_to_laserscan");
  const auto& info =
      *static_cast<const msgs::CameraInfo*>(dataset.stream("camera_info").messages[3].get());
  msgs::LaserScan scan;
  scan.angle_max = static_cast<float>(std::atan2(info.p[2], info.p[0]));
  scan.angle_min = static_cast<float>(-std::atan2(639 - info.p[2], info.p[0]));
  scan.angle_increment = (scan.angle_max - scan.angle_min) / 639;
  scan.range_min = 0.45f;
  scan.range_max = 10.0f;
  scan.ranges.assign(640, 1.0f);
  const auto flat = std::make_shared<const msgs::LaserScan>(scan);
  const FunctionalResult f = evaluate_functional(*spec.functional, dataset, {{3, flat}}, 1);
  EXPECT_FALSE(f.valid);
  EXPECT_GT(metric(f, "mean_error_m").value, 1.0);
  EXPECT_NE(reasons(f).find("max_error_m"), std::string::npos) << reasons(f);

  scan.ranges.assign(640, std::nanf(""));
  const auto empty = std::make_shared<const msgs::LaserScan>(scan);
  const FunctionalResult g = evaluate_functional(*spec.functional, dataset, {{3, empty}}, 1);
  EXPECT_FALSE(g.valid);
  EXPECT_EQ(metric(g, "valid_fraction").value, 0.0);
}

// n1/n2: the payload dataset is what the workload asks for, and the echo evaluator finds a single
// changed byte, whatever the stamp (which carries the message ID) says.
TEST(Functional, EchoEvaluatorFindsAChangedPayloadByte) {
  const BenchmarkSpec spec =
      load_benchmark(kBenchmarks.parent_path() / "middleware" / "n1_intra_process");
  const Dataset dataset = load_dataset("middleware/payload", {{"payload_bytes", "1000"}});
  ASSERT_EQ(dataset.frames, 100u);
  const auto& sent = *static_cast<const msgs::Image*>(dataset.stream("payload").messages[7].get());
  EXPECT_EQ(sent.data.size(), 1000u);
  EXPECT_EQ(sent.encoding, "8UC1");
  const auto& other = *static_cast<const msgs::Image*>(dataset.stream("payload").messages[8].get());
  EXPECT_NE(sent.data, other.data) << "every frame has its own payload";

  msgs::Image echo = sent;
  echo.header.stamp = msgs::Time{1795000000, 42};  // an ID, as the Playback stamps it
  msgs::Image changed = echo;
  changed.data[999] ^= 1;
  const FunctionalResult good = evaluate_functional(
      *spec.functional, dataset, {{7, std::make_shared<const msgs::Image>(echo)}}, 1);
  EXPECT_TRUE(good.valid) << reasons(good);
  EXPECT_EQ(metric(good, "identical_fraction").value, 1.0);
  const FunctionalResult bad = evaluate_functional(
      *spec.functional, dataset,
      {{7, std::make_shared<const msgs::Image>(echo)},
       {107, std::make_shared<const msgs::Image>(changed)}},  // 107: frame 7 again (the run loops)
      2);
  EXPECT_FALSE(bad.valid);
  EXPECT_EQ(metric(bad, "identical_fraction").value, 0.5);

  EXPECT_THROW(load_dataset("middleware/payload", {{"payload_bytes", "0"}}), std::invalid_argument);
  // 256 MiB payloads in the default 100 frames would be 25 GiB held: refused before any is made,
  // naming the frames that fit.
  try {
    load_dataset("middleware/payload", {{"payload_bytes", "268435456"}});
    ADD_FAILURE() << "25 GiB of payloads were accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("--workload frames=4"), std::string::npos) << e.what();
  }
}

TEST(Functional, SampleIdsAreSpreadOverTheMeasuredMessages) {
  EXPECT_EQ(functional_sample_ids(10, 2, 4), (std::vector<uint64_t>{2, 4, 6, 8}));
  EXPECT_EQ(functional_sample_ids(5, 2, 0), (std::vector<uint64_t>{2, 3, 4}));
  EXPECT_EQ(functional_sample_ids(5, 2, 9), (std::vector<uint64_t>{2, 3, 4}));
  EXPECT_TRUE(functional_sample_ids(5, 5, 3).empty());
}

// graph.yaml of a3 (or b3) with `functional:` replaced.
std::string graph_with(const fs::path& package, const std::string& functional) {
  std::string g = read(package / "graph.yaml");
  return g.substr(0, g.find("\nfunctional:") + 1) + functional;
}
std::string a3_graph_with(const std::string& functional) {
  return graph_with(kBenchmarks / "a3_stereo_image_proc", functional);
}
std::string b3_graph_with(const std::string& functional) {
  return graph_with(kBenchmarks.parent_path() / "localization" / "b3_apriltag_detection",
                    functional);
}

TEST(Functional, BadFunctionalSectionsAreReportedWithFileAndLine) {
  auto error_of = [](const std::string& graph, const std::string& meta_extra = "") {
    testing::TestPackage p("badfunctional", graph);
    if (!meta_extra.empty()) std::ofstream(p.dir() / "benchmark.yaml", std::ios::app) << meta_extra;
    try {
      load_benchmark(p.dir());
    } catch (const BenchmarkError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(error_of(a3_graph_with("functional: {evaluator: psychic, truth: {}}\n"))
                .find("unknown functional evaluator 'psychic'"),
            std::string::npos);
  EXPECT_NE(error_of(a3_graph_with("functional: {evaluator: depth_point_cloud, truth: {}}\n"))
                .find("reads sensor_msgs/msg/PointCloud2"),
            std::string::npos);
  EXPECT_NE(error_of(a3_graph_with("functional: {evaluator: stereo_disparity, truth: {}}\n"))
                .find("needs truth stream 'disparity'"),
            std::string::npos);
  // The second topic: only for evaluators that read one, and named once.
  EXPECT_NE(error_of(a3_graph_with("functional: {evaluator: stereo_disparity, truth: {disparity: "
                                   "d}, second_output: /x}\n"))
                .find("takes no observed_truth or second_output"),
            std::string::npos);
  EXPECT_NE(
      error_of(b3_graph_with("functional: {evaluator: apriltag_detection, truth: {tags: t, "
                             "poses: p}}\n"))
          .find("needs an observed_truth or second_output topic (geometry_msgs/msg/PoseArray)"),
      std::string::npos);
  EXPECT_NE(error_of(b3_graph_with("functional: {evaluator: apriltag_detection, truth: {tags: t, "
                                   "poses: p}, second_output: /a, observed_truth: /b}\n"))
                .find("not both"),
            std::string::npos);
  const std::string ok = "functional: {evaluator: stereo_disparity, truth: {disparity: d}}\n";
  const std::string e =
      error_of(a3_graph_with(ok), "functional:\n  thresholds:\n    bad2: {max: 1}\n");
  EXPECT_NE(e.find("benchmark.yaml:"), std::string::npos) << e;
  EXPECT_NE(e.find("no metric 'bad2'"), std::string::npos) << e;
  EXPECT_NE(error_of(a3_graph_with(""), "functional:\n  thresholds:\n    bad1: {max: 1}\n")
                .find("names no functional evaluator"),
            std::string::npos);
}

TEST(Functional, MissingTruthStreamFailsBeforeTiming) {
  const PackageCopy wrong("a3_stereo_image_proc", "x6", [](std::string g) {
    return replace_all(g, "{disparity: disparity_truth}", "{disparity: no_such_stream}");
  });
  EXPECT_THROW(run_benchmark(wrong.spec(), quick(4, 10)), std::invalid_argument);
}

}  // namespace
}  // namespace robotperf::harness
