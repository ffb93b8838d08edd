// Names from a benchmark package become parts of file names: none may lead out of the folder.
#include "robotperf/files/paths.hpp"

#include <gtest/gtest.h>

#include <stdexcept>

namespace robotperf::files {
namespace {

TEST(Paths, ANameStaysInsideItsFolderOrIsRefused) {
  for (const char* folder : {"o1", "o1/", "./o1", "/tmp/o1"}) {
    EXPECT_TRUE(is_inside(folder, std::filesystem::path(folder) / "a1-intra-1.json")) << folder;
    EXPECT_TRUE(is_inside(folder, std::filesystem::path(folder) / "x..y.json")) << folder;
    for (const char* name : {"../a1.json", "../../ESCAPED-intra.json", "/abs/ABSOLUTE-intra.json",
                             "", ".", "x/../../y.json"}) {
      EXPECT_FALSE(is_inside(folder, std::filesystem::path(folder) / name))
          << folder << " + " << name;
      EXPECT_THROW(path_inside(folder, name), std::invalid_argument) << folder << " + " << name;
    }
  }
  EXPECT_EQ(path_inside("o1", "a1.json"), std::filesystem::path("o1/a1.json"));
  EXPECT_THROW(path_inside("o1", "a1\n.json"), std::invalid_argument);
}

}  // namespace
}  // namespace robotperf::files
