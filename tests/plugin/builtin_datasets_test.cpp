// The built-in categories' datasets keep the promises of the plug-in API: each generates the
// streams it describes, one message per frame, as many frames as it says for its default workload,
// and the same bytes every time.
#include <gtest/gtest.h>

#include "robotperf/harness/dataset.hpp"
#include "robotperf/plugin/registry.hpp"

namespace robotperf::plugin {
namespace {

TEST(BuiltInDatasets, EachIsAsDescribedAndDeterministic) {
#ifdef __SANITIZE_ADDRESS__
  // Rendering and sampling every dataset twice takes over the 300 s test limit in a sanitized
  // Debug build (22 s optimised): run this program on its own there.
  GTEST_SKIP() << "too slow for the test time limit in a sanitized build";
#endif
  std::size_t checked = 0;
  for (const DatasetEntry* entry : registry().datasets()) {
    if (!entry->origin.starts_with("built-in ")) continue;
    const auto& info = entry->info;
    // load_dataset checks the streams against the description.
    const harness::Dataset first = harness::load_dataset(info.name);
    EXPECT_EQ(first.frames, info.frames) << info.name;
    EXPECT_EQ(first.rate_hz, info.rate_hz) << info.name;
    ASSERT_EQ(first.streams.size(), info.streams.size()) << info.name;
    // A second generation, past the loader's cache, gives the same content.
    const std::vector<DatasetStream> again =
        entry->generate(Parameters(info.workload, {}, info.name));
    EXPECT_EQ(harness::content_hash(again), first.hash) << info.name;
    ++checked;
  }
  EXPECT_GE(checked, 9u);
}

}  // namespace
}  // namespace robotperf::plugin
