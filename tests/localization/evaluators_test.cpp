// The localization evaluators judge what the kernels answer: right answers pass b1-b3's
// thresholds, and a kernel fed or configured wrongly is caught.
#include <gtest/gtest.h>

#include <cmath>

#include "robotperf/localization/scan_matcher.hpp"
#include "robotperf/msgs/geometry_msgs.hpp"
#include "robotperf/msgs/nav_msgs.hpp"
#include "robotperf/msgs/sensor_msgs.hpp"
#include "robotperf/plugin/registry.hpp"

namespace robotperf::localization {
namespace {

using plugin::registry;

struct Streams {
  std::vector<plugin::DatasetStream> streams;
  const plugin::DatasetStream& operator[](const std::string& name) const {
    for (const auto& s : streams)
      if (s.name == name) return s;
    throw std::invalid_argument("no stream " + name);
  }
};

Streams generate(const std::string& dataset) {
  const auto* entry = registry().find_dataset(dataset);
  EXPECT_NE(entry, nullptr) << dataset;
  return {entry->generate(plugin::Parameters(entry->info.workload, {}, "test"))};
}

std::unique_ptr<plugin::FunctionalEvaluator> evaluator(
    const std::string& name, std::map<std::string, const plugin::DatasetStream*> truth) {
  const auto* entry = registry().find_evaluator(name);
  EXPECT_NE(entry, nullptr) << name;
  return entry->make(plugin::TruthStreams(name, std::move(truth)),
                     plugin::Parameters(entry->info.parameters, {}, "test"));
}

// b2: the localizer's answers on the dataset's scans, and on the same scans from a scanner whose
// ranges read 20 % long (a miscalibration), which must fail the success threshold.
TEST(LocalizationEvaluators, MapLocalizationPassesAndAMiscalibratedScannerFails) {
  const Streams data = generate("localization/map_scans");
  const auto& grid = *static_cast<const msgs::OccupancyGrid*>(data["map"].messages[0].get());
  GridMap map{grid.info.width,
              grid.info.height,
              grid.info.resolution,
              grid.info.origin.position.x,
              grid.info.origin.position.y,
              grid.data};
  const GlobalLocalizer localizer(map);
  auto judge = [&](double range_scale, std::size_t frames) {
    auto e = evaluator("map_localization", {{"pose", &data["pose_truth"]}});
    for (std::size_t k = 0; k < frames; ++k) {
      const auto& in = *static_cast<const msgs::LaserScan*>(data["scan"].messages[k].get());
      Scan scan{in.angle_min, in.angle_increment, in.range_min, in.range_max, in.ranges};
      for (float& r : scan.ranges) r *= static_cast<float>(range_scale);
      const LocalizationResult r = localizer.localize(scan);
      msgs::PoseWithCovarianceStamped out;
      out.header.frame_id = "map";
      out.pose.pose.position = {r.x, r.y, 0.0};
      out.pose.pose.orientation = {0.0, 0.0, std::sin(r.yaw / 2), std::cos(r.yaw / 2)};
      const std::size_t index[3] = {0, 1, 5};
      for (std::size_t i = 0; i < 3; ++i)
        for (std::size_t j = 0; j < 3; ++j)
          out.pose.covariance[6 * index[i] + index[j]] = r.covariance[3 * i + j];
      e->add(&out, k);
    }
    EXPECT_TRUE(e->problems().empty());
    return e->metrics();
  };
  const auto good = judge(1.0, data["scan"].messages.size());
  EXPECT_GE(good.at("success_rate"), 0.98);
  EXPECT_LE(good.at("position_error_median_m"), 0.05);
  EXPECT_LE(good.at("yaw_error_median_deg"), 1.0);
  EXPECT_GE(good.at("covariance_coverage"), 0.9);
  const auto bad = judge(1.2, 10);
  EXPECT_LT(bad.at("success_rate"), 0.5);
}

TEST(LocalizationEvaluators, AnAnswerInAnotherFrameIsADefect) {
  const Streams data = generate("localization/map_scans");
  auto e = evaluator("map_localization", {{"pose", &data["pose_truth"]}});
  msgs::PoseWithCovarianceStamped out;
  out.header.frame_id = "odom";
  e->add(&out, 0);
  ASSERT_EQ(e->problems().size(), 1u);
  EXPECT_NE(e->problems().begin()->find("pose frame is 'odom', expected 'map'"), std::string::npos);
}

}  // namespace
}  // namespace robotperf::localization
