#include "ema/core/types.hpp"

#include <gtest/gtest.h>

#include <limits>

namespace ema {
namespace {

TEST(Direction, OneAxisTable) {
  // AxisCode is the table DirectionName, ParseDirection and the UFF entity names share.
  EXPECT_EQ(AxisCode("X"), 1);
  EXPECT_EQ(AxisCode("rz"), 6);
  EXPECT_EQ(AxisCode("+X"), 0);  // unsigned: the sign is the caller's
  EXPECT_EQ(AxisCode("Q"), 0);
  EXPECT_EQ(AxisCode("XR"), 0);
  EXPECT_EQ(ParseDirection("-ry"), -5);
  EXPECT_EQ(ParseDirection("+-X"), 0);
}

TEST(Direction, NamesRoundTrip) {
  for (int code : {1, 2, 3, 4, 5, 6, -1, -2, -3, -4, -5, -6}) {
    EXPECT_EQ(ParseDirection(DirectionName(code)), code) << DirectionName(code);
  }
  EXPECT_EQ(DirectionName(-3), "-Z");
  EXPECT_EQ(ParseDirection("x"), 1);
  EXPECT_EQ(ParseDirection("+Q"), 0);
}

TEST(Direction, CodesOutsideTheAxesAreNamedWithoutOverflow) {
  // A code no reader makes is still printable (a fuzzed typed result, a corrupt record); the
  // negation for INT_MIN overflowed before (UBSan: "negation of -2147483648 cannot be represented").
  EXPECT_EQ(DirectionName(7), "?7");
  EXPECT_EQ(DirectionName(-7), "?-7");
  EXPECT_EQ(DirectionName(std::numeric_limits<int>::min()), "?-2147483648");
  EXPECT_EQ(DirectionName(std::numeric_limits<int>::max()), "?2147483647");
  EXPECT_EQ(DirectionName(0), "S");
}

TEST(Pole, FrequencyAndDampingRoundTrip) {
  // 1e-12: the conversion is a handful of floating-point operations.
  for (double zeta : {0.0, 0.001, 0.05, 0.3}) {
    double f = 0.0, z = 0.0;
    PoleToFrequencyAndDamping(FrequencyAndDampingToPole(123.4, zeta), &f, &z);
    EXPECT_NEAR(f, 123.4, 1e-9);
    EXPECT_NEAR(z, zeta, 1e-12);
  }
}

}  // namespace
}  // namespace ema
