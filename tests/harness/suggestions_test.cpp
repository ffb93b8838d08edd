// The nearest name to a typo: near enough for the word's length, unique, whatever the case.
#include "robotperf/harness/suggestions.hpp"

#include <gtest/gtest.h>

namespace robotperf::harness {
namespace {

const std::vector<std::string> kVerbs = {"list", "describe", "run", "results", "report",
                                         "compare", "trace", "bag", "dataset"};

TEST(NearestName, FindsOneEditTypos) {
  EXPECT_EQ(nearest_name("descrbe", kVerbs), "describe");  // a letter missing
  EXPECT_EQ(nearest_name("lsit", kVerbs), "list");         // two neighbours swapped
  EXPECT_EQ(nearest_name("rum", kVerbs), "run");           // a letter changed
  EXPECT_EQ(nearest_name("Compare", kVerbs), "compare");   // case
  EXPECT_EQ(nearest_name("reportt", kVerbs), "report");    // a letter added
}

TEST(NearestName, AllowsMoreEditsOnlyInLongerWords) {
  EXPECT_EQ(nearest_name("dtaset", kVerbs), "dataset");
  EXPECT_EQ(nearest_name("datsaet", kVerbs), "dataset");  // two edits in 7 letters
  EXPECT_EQ(nearest_name("bgx", kVerbs), std::nullopt);   // two edits in 3 letters
  EXPECT_EQ(nearest_name("frobnicate", kVerbs), std::nullopt);
}

TEST(NearestName, GuessesNothingBetweenTwoAlikeOrForAnExactName) {
  EXPECT_EQ(nearest_name("a6", {"a1", "a2", "a5", "b1"}), std::nullopt);
  EXPECT_EQ(nearest_name("a11", {"a1", "a2", "b1"}), "a1");
  EXPECT_EQ(nearest_name("run", kVerbs), std::nullopt);
  EXPECT_EQ(did_you_mean("rnu", kVerbs), "; did you mean 'run'?");
  EXPECT_EQ(did_you_mean("xyz", kVerbs), "");
}

}  // namespace
}  // namespace robotperf::harness
