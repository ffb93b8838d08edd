// "Did you mean": the name a mistyped word was probably meant to be, for the one line that says
// a benchmark id, a verb or an option is unknown.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace robotperf::harness {

// The candidate nearest `word` by edit distance (a letter inserted, removed, changed, or two
// neighbours swapped), compared without case, when it is near enough to be a typo of it: one
// edit for words of up to four letters, two up to eight, three beyond. Nothing when no candidate
// is that near, or when two tie for nearest (a guess between them would mislead).
std::optional<std::string> nearest_name(std::string_view word,
                                        const std::vector<std::string>& candidates);

// "; did you mean 'x'?" for nearest_name's answer, or "" when it has none.
std::string did_you_mean(std::string_view word, const std::vector<std::string>& candidates);

}  // namespace robotperf::harness
