// The tf2 buffer's lookupTransform against a direct computation of the same transform (issue
// #52: overhead <= 2x). Run on demand: ./build/bench/tf2/bench_tf2
//
// The tree: 50 frames, a root and two branches of 25 and 24 dynamic frames, each sampled at
// 10 Hz for 10 s (the default cache). One lookup goes from one leaf to the other at a time
// between samples: 49 edges, each interpolated (linear and SLERP) and composed. The direct
// computation does exactly that arithmetic on the same samples, with the path and each sample's
// index known beforehand: what the buffer adds is finding the frames, walking the tree, searching
// the samples and its lock. Each figure is the median of batches of lookups, the two sides taken
// in turns.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "robotperf/plugin/tf2_buffer.hpp"
#include "this_build.hpp"

using namespace robotperf;
using plugin::RigidTransform;

namespace {

constexpr int kBranchA = 25, kBranchB = 24;  // with the root: 50 frames
constexpr int kSamples = 100;
constexpr int64_t kPeriodNs = 100'000'000;  // 10 Hz
constexpr int64_t kStartNs = 1'000'000'000;
constexpr int kBatch = 200, kBatches = 200;
constexpr double kTarget = 2.0;

RigidTransform sample_transform(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-1, 1);
  RigidTransform t;
  t.translation = {u(rng), u(rng), u(rng)};
  const double angle = u(rng) * 3;
  const double ax = u(rng), ay = u(rng), az = u(rng);
  const double n = std::sqrt(ax * ax + ay * ay + az * az);
  const double s = std::sin(angle / 2) / n;
  t.rotation = {ax * s, ay * s, az * s, std::cos(angle / 2)};
  return t;
}

// One branch's frames from its leaf up, each with its samples.
struct Branch {
  std::vector<std::vector<RigidTransform>> samples;  // [frame from the leaf][sample]
};

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

}  // namespace

int main() {
  bench::warn_about_this_build();
  std::mt19937_64 rng(52);
  plugin::TransformBuffer buffer("bench");
  Branch a, b;
  auto fill = [&](Branch& branch, const std::string& prefix, int frames) {
    branch.samples.resize(frames);
    // From the root down, so that each frame's parent exists; stored leaf first.
    for (int depth = 1; depth <= frames; ++depth) {
      auto& samples = branch.samples[frames - depth];
      const std::string parent = depth == 1 ? "world" : prefix + std::to_string(depth - 1);
      for (int k = 0; k < kSamples; ++k) {
        samples.push_back(sample_transform(rng));
        msgs::TransformStamped t;
        t.header.frame_id = parent;
        t.header.stamp = msgs::Time::from_ns(kStartNs + k * kPeriodNs);
        t.child_frame_id = prefix + std::to_string(depth);
        t.transform = samples.back().to_msg();
        buffer.set_transform(t, "bench", false);
      }
    }
  };
  fill(a, "a", kBranchA);
  fill(b, "b", kBranchB);
  const std::string source = "a" + std::to_string(kBranchA);
  const std::string target = "b" + std::to_string(kBranchB);

  // The times of one batch, between samples; the same for both sides.
  std::uniform_int_distribution<int64_t> when(kStartNs, kStartNs + (kSamples - 1) * kPeriodNs - 1);
  std::vector<int64_t> times(kBatch);
  for (auto& t : times) t = when(rng);

  auto direct = [&](int64_t time) {
    const int64_t since = time - kStartNs;
    const auto k = static_cast<std::size_t>(since / kPeriodNs);
    const double fraction = static_cast<double>(since % kPeriodNs) / static_cast<double>(kPeriodNs);
    auto up = [&](const Branch& branch) {
      RigidTransform to_root;
      for (const auto& s : branch.samples)
        to_root = plugin::interpolate(s[k], s[k + 1], fraction) * to_root;
      return to_root;
    };
    return up(b).inverse() * up(a);
  };

  // Both sides agree before they are timed.
  double worst = 0;
  for (int64_t t : times) {
    const auto looked_up = buffer.lookup_transform(target, source, t).transform;
    const auto computed = direct(t).to_msg();
    worst = std::max({worst, std::abs(looked_up.translation.x - computed.translation.x),
                      std::abs(looked_up.translation.y - computed.translation.y),
                      std::abs(looked_up.translation.z - computed.translation.z)});
  }
  if (worst > 1e-9) {
    std::fprintf(stderr, "bench_tf2: lookup and direct computation differ by %g m\n", worst);
    return 1;
  }

  using Clock = std::chrono::steady_clock;
  volatile double sink = 0;
  std::vector<double> lookup_ns, direct_ns;
  for (int batch = 0; batch < kBatches; ++batch) {
    auto t0 = Clock::now();
    for (int64_t t : times)
      sink = sink + buffer.lookup_transform(target, source, t).transform.translation.x;
    auto t1 = Clock::now();
    for (int64_t t : times) sink = sink + direct(t).translation[0];
    auto t2 = Clock::now();
    lookup_ns.push_back(std::chrono::duration<double, std::nano>(t1 - t0).count() / kBatch);
    direct_ns.push_back(std::chrono::duration<double, std::nano>(t2 - t1).count() / kBatch);
  }
  const double figure = median(lookup_ns), reference = median(direct_ns);
  const double ratio = figure / reference;
  std::printf("lookupTransform on a 50-frame tree (leaf to leaf, %d edges interpolated)\n",
              kBranchA + kBranchB);
  std::printf("  figure     %9.0f ns/op  TransformBuffer::lookup_transform\n", figure);
  std::printf("  reference  %9.0f ns/op  direct computation (path and sample indices known)\n",
              reference);
  std::printf("  ratio      %9.2f       target <= %.1f  %s\n", ratio, kTarget,
              ratio <= kTarget ? "(met)" : "(NOT met)");
  return 0;
}
