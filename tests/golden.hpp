#pragma once
// Golden numbers (tests/data/golden/): results written by an earlier version of the program, which
// a change that should keep them (issue 38: the run as one typed pipeline) must give again.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <string>

namespace ema::test {

/// How far the same code on the same data may land from the golden numbers on another x86-64
/// machine. Round-off differs between machines and the fits amplify it: measured 2026-11-29 between
/// the machine that wrote the golden files and a fresh one (an Emerald Rapids guest; not OpenBLAS's
/// kernels — OPENBLAS_CORETYPE changed none of the numbers there): up to 5e-5 relative in the
/// bolted frame's diagnosis and fitted modes, and 0.02 in the −2 ln Z of candidates far down a
/// list (probability ~1e-4: loosely determined fits). On the machine that wrote them the numbers
/// agree to 1e-12; a real change of the computation (a prior, a residual, the model error) moves
/// them by percent.
inline constexpr double kGoldenRelative = 1e-4;
/// Scores (−2 ln Z) compare absolutely: 0.05 moves a probability by 2.5 % of itself.
inline constexpr double kGoldenScore = 0.05;

/// Every number and string of `golden` equal in `actual` — numbers to `relative` of max(1, |g|),
/// "score" values to kGoldenScore. Keys `actual` adds are not compared. Counts the values compared
/// in *compared.
inline void ExpectSameNumbers(const nlohmann::json& golden, const nlohmann::json& actual, const std::string& path,
                              int* compared, double relative = kGoldenRelative) {
  if (golden.is_object()) {
    ASSERT_TRUE(actual.is_object()) << path;
    for (auto it = golden.begin(); it != golden.end(); ++it) {
      ASSERT_TRUE(actual.contains(it.key())) << path << "/" << it.key();
      ExpectSameNumbers(it.value(), actual[it.key()], path + "/" + it.key(), compared, relative);
    }
  } else if (golden.is_array()) {
    ASSERT_TRUE(actual.is_array()) << path;
    ASSERT_EQ(golden.size(), actual.size()) << path;
    for (std::size_t i = 0; i < golden.size(); ++i)
      ExpectSameNumbers(golden[i], actual[i], path + "[" + std::to_string(i) + "]", compared, relative);
  } else if (golden.is_number()) {
    ASSERT_TRUE(actual.is_number()) << path;
    const double g = golden.get<double>(), a = actual.get<double>();
    const bool score = path.size() >= 6 && path.compare(path.size() - 6, 6, "/score") == 0;
    EXPECT_NEAR(a, g, score ? kGoldenScore : relative * std::max(1.0, std::abs(g))) << path;
    ++*compared;
  } else {
    EXPECT_EQ(golden, actual) << path;
    ++*compared;
  }
}

}  // namespace ema::test
