#pragma once
// Golden numbers (tests/data/golden/): results written by an earlier version of the program, which
// a change that should keep them (issue 38: the run as one typed pipeline) must give again.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <string>

namespace ema::test {

/// Every number and string of `golden` equal in `actual` — numbers to `relative` (1e-9: the same
/// code on the same data; a real change of the computation moves them far more). Keys `actual`
/// adds are not compared. Counts the values compared in *compared.
inline void ExpectSameNumbers(const nlohmann::json& golden, const nlohmann::json& actual, const std::string& path,
                              int* compared, double relative = 1e-9) {
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
    EXPECT_NEAR(a, g, relative * std::max(1.0, std::abs(g))) << path;
    ++*compared;
  } else {
    EXPECT_EQ(golden, actual) << path;
    ++*compared;
  }
}

}  // namespace ema::test
