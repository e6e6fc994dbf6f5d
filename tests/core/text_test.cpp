// ema/core/text.hpp: the one fixed-point rule and the one HTML escape.
#include "ema/core/text.hpp"

#include <gtest/gtest.h>

#include <limits>

#include "ema/core/types.hpp"

namespace ema {
namespace {

TEST(Text, FixedPointRoundsAndNamesNonFiniteValues) {
  EXPECT_EQ(FixedPoint(95.04, 1), "95.0");
  EXPECT_EQ(FixedPoint(-0.0004, 3), "-0.000");  // printf keeps the sign of a rounded negative
  EXPECT_EQ(FixedPoint(2.5, 0), "2");           // round half to even, as printf does
  EXPECT_EQ(FixedPoint(kNaN, 2), "");
  EXPECT_EQ(FixedPoint(kNaN, 2, "–"), "–");
  EXPECT_EQ(FixedPoint(std::numeric_limits<double>::infinity(), 1, "-"), "-");
  EXPECT_EQ(FixedPoint(1e300, 1).size(), 303u);  // 301 digits, the point, one decimal: never cut
}

TEST(Text, HtmlEscapeCoversContentAndAttributes) {
  EXPECT_EQ(HtmlEscape("a < b && c > \"d\""), "a &lt; b &amp;&amp; c &gt; &quot;d&quot;");
  EXPECT_EQ(HtmlEscape("Δf [%] 'x'"), "Δf [%] 'x'");  // UTF-8 and single quotes pass through
}

}  // namespace
}  // namespace ema
