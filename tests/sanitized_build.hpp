// Whether this is a sanitized build (-DROBOTPERF_SANITIZE=ON). AddressSanitizer gives every large
// allocation fresh pages of its own, so a graph of megabyte images runs ten times slower or more
// there: a run at the rate a normal build keeps up with falls behind, loses messages and is
// invalid. End-to-end tests whose point is not the rate run slower in such a build; those whose
// point is the rate skip there, saying why.
#pragma once

#include <string>

#if defined(__SANITIZE_ADDRESS__)
inline constexpr bool kSanitizedBuild = true;
#else
inline constexpr bool kSanitizedBuild = false;
#endif

// `hz` in a normal build, `sanitized_hz` in a sanitized one.
inline double test_rate(double hz, double sanitized_hz) {
  return kSanitizedBuild ? sanitized_hz : hz;
}

// As a CLI option: " --rate HZ" with test_rate's choice (whole numbers print without decimals).
inline std::string rate_option(double hz, double sanitized_hz) {
  std::string text = std::to_string(test_rate(hz, sanitized_hz));
  text.erase(text.find_last_not_of('0') + 1);
  if (text.back() == '.') text.pop_back();
  return " --rate " + text;
}

// For a run at its benchmark's own rate: nothing in a normal build, " --rate HZ" in a sanitized
// one.
inline std::string sanitized_rate_option(double sanitized_hz) {
  return kSanitizedBuild ? rate_option(sanitized_hz, sanitized_hz) : std::string();
}

// The reason a test whose point is its rate gives for skipping in a sanitized build.
inline constexpr const char* kRateNeedsUnsanitizedBuild =
    "this test's point is keeping up with its rate, which a sanitized build cannot";
