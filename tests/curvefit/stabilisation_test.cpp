// Stabilisation labels and pole selection on hand-made diagrams (issue 28): every label from a
// known pair of poles, the one-to-one matching, automatic selection's clusters (kept, too short,
// drifting, split and merged close pairs), the narrow-band retry and the pick near a frequency.
#include <gtest/gtest.h>

#include <string>

#include "ema/core/error.hpp"
#include "ema/curvefit/fit.hpp"
#include "ema/curvefit/stabilisation.hpp"

namespace ema::curvefit {
namespace {

Eigen::VectorXcd Vec(double a, double b) {
  Eigen::VectorXcd v(2);
  v << a, b;
  return v.normalized();
}

Pole MakePole(int order, double f_hz, double zeta, const Eigen::VectorXcd& participation, bool physical = true) {
  Pole p;
  p.order = order;
  p.lambda = p.lambda_fitted = FrequencyAndDampingToPole(f_hz, zeta);
  p.frequency_hz = f_hz;
  p.damping_ratio = zeta;
  p.participation = participation;
  p.physical = physical;
  return p;
}

// orders[k] holds order k + 1; `lines` lines in the band.
StabilisationDiagram Diagram(int n_orders, int lines = 400) {
  StabilisationDiagram d;
  d.order_min = 1;
  d.order_max = n_orders;
  d.orders.resize(n_orders);
  d.references = 2;
  d.frequency_hz = Eigen::VectorXd::LinSpaced(lines, 1.0, 200.0);
  d.band_lo_hz = 1.0;
  d.band_hi_hz = 200.0;
  return d;
}

// Defaults: frequency 1 %, damping 5 %, MAC 0.98. Each order holds one pole compared with the
// previous order's: the label follows from which of the three criteria hold.
TEST(ClassifyStability, EachLabelFromAKnownPair) {
  const Eigen::VectorXcd v = Vec(1.0, 0.5), w = Vec(0.5, -1.0);  // MAC(v, w) = 0
  StabilisationDiagram d = Diagram(7);
  d.orders[0] = {MakePole(1, 100.0, 0.0100, v)};
  d.orders[1] = {MakePole(2, 100.5, 0.0102, v)};  // 0.5 %, 2 %, same vector: 's'
  d.orders[2] = {MakePole(3, 100.6, 0.0150, v)};  // damping +47 %: 'v'
  d.orders[3] = {MakePole(4, 100.6, 0.0151, w)};  // damping ok, vector orthogonal: 'd'
  d.orders[4] = {MakePole(5, 102.0, 0.0151, w)};  // 1.4 % away: no match, 'o'
  d.orders[5] = {MakePole(6, 102.1, 0.0300, v)};  // frequency only: 'f'
  d.orders[6] = {MakePole(7, 102.1, 0.0300, v, false)};  // not physical: 'o' whatever it matches
  ClassifyStability(&d);
  const std::string labels = {d.orders[0][0].label, d.orders[1][0].label, d.orders[2][0].label, d.orders[3][0].label,
                              d.orders[4][0].label, d.orders[5][0].label, d.orders[6][0].label};
  EXPECT_EQ(labels, "osvdofo");
  EXPECT_TRUE(std::isnan(d.orders[0][0].match_distance));
  // match distance = |Δλ|/|λ| + (1 − MAC): 0.5 % frequency, 2 % of 1 % damping, MAC 1.
  EXPECT_NEAR(d.orders[1][0].match_distance, 0.005, 2e-4);
  // Tighter tolerances turn the 's' into 'o' (frequency) or 'v' (damping).
  StabilityOptions tight;
  tight.frequency_tol = 0.004;
  ClassifyStability(&d, tight);
  EXPECT_EQ(d.orders[1][0].label, 'o');
  tight = {};
  tight.damping_tol = 0.01;
  ClassifyStability(&d, tight);
  EXPECT_EQ(d.orders[1][0].label, 'v');
}

// Two poles of one order near one pole of the previous order: the nearer takes the match, the
// other stays new (one to one, nearest first).
TEST(ClassifyStability, MatchingIsOneToOneNearestFirst) {
  const Eigen::VectorXcd v = Vec(1.0, 0.2);
  StabilisationDiagram d = Diagram(2);
  d.orders[0] = {MakePole(1, 50.0, 0.01, v)};
  d.orders[1] = {MakePole(2, 49.8, 0.01, v), MakePole(2, 50.1, 0.01, v)};
  ClassifyStability(&d);
  EXPECT_EQ(d.orders[1][0].label, 'o');
  EXPECT_EQ(d.orders[1][1].label, 's');
}

// Orders 1..20: a mode at 50 Hz stable from order 3 (a slow drift of 0.01 % per order, the
// damping falling as the LS bias shrinks), a short column at 80 Hz (orders 17..20: 4 orders, below
// max(4, 0.3 × 20) = 6) and scattered noise poles. Exactly the 50 Hz column is selected, its
// representative from the upper half of the orders, its spread that of its members.
TEST(SelectPolesAuto, KeepsLongColumnsDropsShortOnes) {
  const Eigen::VectorXcd v = Vec(1.0, 0.3), u = Vec(0.2, 1.0);
  StabilisationDiagram d = Diagram(20);
  for (int p = 1; p <= 20; ++p) {
    auto& order = d.orders[p - 1];
    if (p >= 2) order.push_back(MakePole(p, 50.0 * (1.0 + 1e-4 * (p - 10)), 0.0100 + 1e-5 * (20 - p), v));
    if (p >= 16) order.push_back(MakePole(p, 80.0, 0.02, u));
    order.push_back(MakePole(p, 20.0 + 7.3 * p, 0.05 + 0.01 * (p % 3), Vec(p, 1.0)));
  }
  ClassifyStability(&d);
  const std::vector<SelectedPole> sel = SelectPolesAuto(d);
  ASSERT_EQ(sel.size(), 1u);
  EXPECT_EQ(sel[0].first_order, 3);  // order 2 starts the column ('o'), order 3 is its first 's'
  EXPECT_EQ(sel[0].last_order, 20);
  EXPECT_EQ(sel[0].cluster_size, 18);
  // Representative: the medoid of the upper half (orders 12..20, median order of 3..20 is 12), the
  // middle of a steady drift: order 16, 50·(1 + 6e-4) Hz.
  EXPECT_EQ(sel[0].pole.order, 16);
  EXPECT_NEAR(sel[0].pole.frequency_hz, 50.03, 1e-9);
  // Spread: std of 50·1e-4·(p−10) over p = 3..20 = 5e-3 × std(3..20) = 5e-3 × 5.34 Hz.
  EXPECT_NEAR(sel[0].frequency_spread_hz, 5e-3 * 5.338539, 1e-4);
  // Without the span rule (clusters of 4 orders suffice) the 80 Hz column is kept too.
  AutoSelectOptions loose;
  loose.min_span_fraction = 0.0;
  loose.min_orders = 4;
  const std::vector<SelectedPole> both = SelectPolesAuto(d, loose);
  ASSERT_EQ(both.size(), 2u);
  EXPECT_NEAR(both[1].pole.frequency_hz, 80.0, 1e-9);
}

// Two modes 0.4 % apart with orthogonal participation (a close pair seen by two references): both
// columns are kept. The same two columns with one vector are one mode whose column split in two
// (a drift cut it): counted once, by the larger cluster.
TEST(SelectPolesAuto, ClosePairSplitOrMergedByTheirVectors) {
  for (const bool distinct : {true, false}) {
    const Eigen::VectorXcd v = Vec(1.0, 0.0), w = distinct ? Vec(0.0, 1.0) : Vec(1.0, 0.0);
    StabilisationDiagram d = Diagram(16);
    for (int p = 1; p <= 16; ++p) {
      d.orders[p - 1].push_back(MakePole(p, 100.0, 0.005, v));
      if (p >= 4) d.orders[p - 1].push_back(MakePole(p, 100.4, 0.005, w));
    }
    ClassifyStability(&d);
    const std::vector<SelectedPole> sel = SelectPolesAuto(d);
    if (distinct) {
      ASSERT_EQ(sel.size(), 2u);
      EXPECT_NEAR(sel[0].pole.frequency_hz, 100.0, 1e-9);
      EXPECT_NEAR(sel[1].pole.frequency_hz, 100.4, 1e-9);
    } else {
      ASSERT_EQ(sel.size(), 1u) << "one vector: one mode";
      EXPECT_NEAR(sel[0].pole.frequency_hz, 100.0, 1e-9) << "the longer column stands for it";
    }
  }
}

// A column that drifts by 0.6 % between orders 10 and 11 (the estimate jumps when the model
// gains a pole elsewhere): two clusters, one ending where the other begins, count once — by the
// upper (converged) part: so when the fragments are not joined first, and when they are (one
// cluster over both parts, orders 2..24, its representative from the upper half).
TEST(SelectPolesAuto, ColumnCutByADriftCountsOnceByItsUpperPart) {
  const Eigen::VectorXcd v = Vec(1.0, 0.4);
  StabilisationDiagram d = Diagram(24);
  for (int p = 1; p <= 24; ++p) d.orders[p - 1].push_back(MakePole(p, p <= 10 ? 60.0 : 60.36, 0.01, v));
  ClassifyStability(&d);
  AutoSelectOptions o;
  o.cutoff = 0.003;  // below the jump: the two parts are separate clusters
  o.min_span_fraction = 0.0;
  AutoSelectOptions unjoined = o;
  unjoined.fragment_frequency_tol = 0.0;
  const std::vector<SelectedPole> sel = SelectPolesAuto(d, unjoined);
  ASSERT_EQ(sel.size(), 1u);
  EXPECT_NEAR(sel[0].pole.frequency_hz, 60.36, 1e-9);
  EXPECT_EQ(sel[0].first_order, 11);  // order 11 matched order 10 across the jump ('s' at 0.6 %)
  const std::vector<SelectedPole> joined = SelectPolesAuto(d, o);
  ASSERT_EQ(joined.size(), 1u);
  EXPECT_NEAR(joined[0].pole.frequency_hz, 60.36, 1e-9);
  EXPECT_EQ(joined[0].first_order, 2);
  EXPECT_EQ(joined[0].cluster_size, 23);
}

// A column whose vector turns slowly along the orders (1 − MAC ≈ 4e-4 from one order to the next,
// 0.25 from the first to the last: what a mode looks like when two roving sets see it at slightly
// different frequencies) is cut by a tight cut-off into fragments of a few orders, each shorter
// than the span test: joined, it is one mode. A close mode 0.4 % above, seen at the same orders with
// a vector of its own, shares orders with it and stays apart.
TEST(SelectPolesAuto, FragmentsOfAColumnWhoseVectorTurnsAreJoined) {
  StabilisationDiagram d = Diagram(30);
  for (int p = 1; p <= 30; ++p) {
    d.orders[p - 1].push_back(MakePole(p, 100.0, 0.01, Vec(1.0, 0.02 * p)));
    d.orders[p - 1].push_back(MakePole(p, 100.4, 0.01, Vec(-0.02 * p, 1.0)));
  }
  ClassifyStability(&d);
  AutoSelectOptions o;
  o.cutoff = 0.005;  // what the data-driven cut-off is on clean data
  AutoSelectOptions unjoined = o;
  unjoined.fragment_frequency_tol = 0.0;
  EXPECT_TRUE(SelectPolesAuto(d, unjoined).empty()) << "every fragment is shorter than 30 % of the orders";
  const std::vector<SelectedPole> sel = SelectPolesAuto(d, o);
  ASSERT_EQ(sel.size(), 2u);
  EXPECT_NEAR(sel[0].pole.frequency_hz, 100.0, 1e-9);
  EXPECT_NEAR(sel[1].pole.frequency_hz, 100.4, 1e-9);
  EXPECT_EQ(sel[0].cluster_size, 29);  // orders 2..30 ('s'; order 1 has nothing to match)
  EXPECT_EQ(sel[1].cluster_size, 29);
}

// A narrow band (40 lines, 6 orders) whose one mode's damping moves by 10 % per order, as low
// orders do: no pole is 'd' or 's' under the 5 % criterion, so strict selection finds nothing;
// the narrow-band retry (damping to 20 %, clusters over 3 orders) finds the mode and says so.
// A wide band (400 lines) gets no retry.
TEST(SelectPolesNarrowBand, RelaxedCriteriaOnlyForFewLines) {
  const Eigen::VectorXcd v = Vec(1.0, 0.7);
  StabilisationDiagram d = Diagram(6, 40);
  double zeta = 0.01;
  for (int p = 1; p <= 6; ++p, zeta *= 0.9) d.orders[p - 1].push_back(MakePole(p, 80.3, zeta, v));
  ClassifyStability(&d);
  EXPECT_TRUE(SelectPolesAuto(d).empty());
  FitOptions options;
  std::string note;
  const std::vector<SelectedPole> sel = SelectPolesNarrowBand(d, options, &note);
  ASSERT_EQ(sel.size(), 1u);
  EXPECT_NEAR(sel[0].pole.frequency_hz, 80.3, 1e-9);
  EXPECT_NE(note.find("relaxed stability"), std::string::npos) << note;
  StabilisationDiagram wide = d;
  wide.frequency_hz = Eigen::VectorXd::LinSpaced(400, 79.3, 81.3);
  EXPECT_TRUE(SelectPolesNarrowBand(wide, options).empty()) << "400 lines: above narrow_band_max_lines";
}

// --select F: the stable pole nearest F fixes the column, the highest order of that column (same
// label, within 0.5 % in frequency and 25 % in damping) is taken; a stable noise column of other
// damping nearby that reaches a higher order is not. Where no pole is stable, any physical pole
// within 10 %; nothing within 10 %: an error naming the option.
TEST(SelectPolesNear, NearestColumnHighestOrder) {
  const Eigen::VectorXcd v = Vec(1.0, 0.1), u = Vec(0.3, 1.0);
  StabilisationDiagram d = Diagram(13);
  for (int p = 1; p <= 12; ++p) d.orders[p - 1].push_back(MakePole(p, 80.30 + 0.001 * p, 0.003, v));
  for (int p = 6; p <= 13; ++p) d.orders[p - 1].push_back(MakePole(p, 80.32, 0.0006, u));
  d.orders[11].push_back(MakePole(12, 120.0, 0.01, u));
  ClassifyStability(&d);
  ASSERT_EQ(d.orders[12][0].label, 's') << "the noise column is stable too";
  const std::vector<SelectedPole> sel = SelectPolesNear(d, {80.3, 119.0});
  ASSERT_EQ(sel.size(), 2u);
  EXPECT_EQ(sel[0].pole.order, 12);
  EXPECT_NEAR(sel[0].pole.frequency_hz, 80.312, 1e-9);
  EXPECT_NEAR(sel[0].pole.damping_ratio, 0.003, 1e-12);
  EXPECT_NEAR(sel[1].pole.frequency_hz, 120.0, 1e-9) << "no stable pole there: any physical pole";
  EXPECT_THROW(SelectPolesNear(d, {150.0}), InputError);
}

}  // namespace
}  // namespace ema::curvefit
