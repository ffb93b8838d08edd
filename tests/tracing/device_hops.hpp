// A grey-box run of a kernel on a device: its upload, compute and download are hops of their own,
// of every measured message, each longer than nothing and together inside the kernel's hop (what
// bench_backends reports as the split). Shared by the opencl and cuda backends' tests.
#pragma once

#include <gtest/gtest.h>

#include <map>
#include <set>
#include <string>

#include "robotperf/harness/run.hpp"

namespace robotperf::test_support {

// `node`'s device stages in `g` against its kernel's hop ("node: kernel"): `stages` of them, and
// no other (a device-resident node skips the upload or the download).
inline void expect_device_stages_inside_kernel(const harness::RunResult& g, const std::string& node,
                                               const std::string& kernel,
                                               const std::set<std::string>& stages_expected = {
                                                   "upload", "compute", "download"}) {
  ASSERT_TRUE(g.grey.has_value());
  std::map<std::string, const tracing::Hop*> hops;
  for (const auto& h : g.grey->hops) hops[h.label()] = &h;
  const auto whole = hops.find(node + ": " + kernel);
  ASSERT_NE(whole, hops.end()) << node << ": " << kernel;
  double stages = 0;
  for (const char* stage : {"upload", "compute", "download"}) {
    const auto it = hops.find(node + ": device " + stage);
    if (!stages_expected.contains(stage)) {
      EXPECT_EQ(it, hops.end()) << node << " has a device " << stage;
      continue;
    }
    ASSERT_NE(it, hops.end()) << node << ": " << stage;
    EXPECT_EQ(it->second->kind, "device");
    EXPECT_EQ(it->second->duration.count, g.measured) << stage;
    EXPECT_GT(it->second->duration.mean, 0.0) << stage;
    stages += it->second->duration.mean;
  }
  EXPECT_LE(stages, whole->second->duration.mean) << "the stages lie inside the kernel";
}

}  // namespace robotperf::test_support
