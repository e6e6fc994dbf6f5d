// Interface laws and the operating-point solve of series chains.
#include <gtest/gtest.h>

#include <cmath>

#include "ema/core/error.hpp"
#include "ema/model/laws.hpp"

namespace ema::model {
namespace {

// An analytic load-lift curve W(h) = W0 exp(-h/h0), tabulated densely; the independent solution
// below uses the analytic function itself, so the comparison also checks the interpolant.
constexpr double kW0 = 400.0, kH0 = 4e-6;
double W(double h) { return kW0 * std::exp(-h / kH0); }
double DW(double h) { return -W(h) / kH0; }

AirFilmLaw Film(int n = 401) {
  AirFilmLaw a;
  for (int i = 0; i < n; ++i) {
    const double h = 1e-6 + 29e-6 * i / (n - 1);
    a.gap.push_back(h);
    a.load.push_back(W(h));
  }
  a.operating_gap = 5e-6;
  return a;
}

TEST(Laws, LinearAndTwoElementLinearChainMatchHandValues) {
  EXPECT_DOUBLE_EQ(LinearizeLaw(LinearLaw{3e6}, "t").stiffness, 3e6);
  // Two springs in series carrying F = 30 N: d = F/k1 + F/k2 = 30/1e6 + 30/3e6 = 40 um,
  // k = 1/(1/1e6 + 1/3e6) = 0.75e6 (hand values, exact in floating point to 1e-12 rel).
  SeriesLaw s{{LinearLaw{1e6}, LinearLaw{3e6}}, 0.0, 30.0};
  const SpringState st = LinearizeLaw(s, "t");
  EXPECT_NEAR(st.stiffness, 0.75e6, 1e-6);
  EXPECT_NEAR(st.deflection, 40e-6, 1e-18);
  ASSERT_EQ(st.element_deflections.size(), 2u);
  EXPECT_NEAR(st.element_deflections[0], 30e-6, 1e-18);
  EXPECT_NEAR(st.element_deflections[1], 10e-6, 1e-18);
}

TEST(Laws, HertzForceAndStiffnessFollowEq75) {
  HertzLaw h;
  h.modulus = 115e9;
  h.radius = 2e-3;
  h.offset = 1e-6;
  h.operating_deflection = 3e-6;  // 2 um of penetration
  const SpringState st = LinearizeLaw(h, "t");
  const double pen = 2e-6;
  EXPECT_NEAR(st.force, 4.0 / 3.0 * 115e9 * std::sqrt(2e-3) * std::pow(pen, 1.5), 1e-9);
  EXPECT_NEAR(st.stiffness, 2 * 115e9 * std::sqrt(2e-3 * pen), 1e-3);
  // The same state given as a preload force.
  HertzLaw hf = h;
  hf.operating_deflection.reset();
  hf.operating_force = st.force;
  EXPECT_NEAR(LinearizeLaw(hf, "t").stiffness, st.stiffness, 1e-6 * st.stiffness);
}

TEST(Laws, AirFilmStiffnessIsMinusSlopeOfLoadLiftCurve) {
  const SpringState st = LinearizeLaw(Film(), "t");
  // Monotone cubic on a 72.5 nm grid: slope error well below 1e-4 relative for this curve.
  EXPECT_NEAR(st.stiffness, -DW(5e-6), 1e-4 * -DW(5e-6));
  EXPECT_NEAR(st.force, W(5e-6), 1e-6 * W(5e-6));
}

TEST(Laws, TableLawSlopeAtOperatingPoint) {
  TableLaw t;
  for (int i = 0; i <= 50; ++i) {
    const double d = 1e-6 * i;
    t.deflection.push_back(d);
    t.force.push_back(1e6 * d + 2e11 * d * d);  // k(d) = 1e6 + 4e11 d
  }
  t.operating_deflection = 20e-6;
  EXPECT_NEAR(LinearizeLaw(t, "t").stiffness, 1e6 + 4e11 * 20e-6, 1e-3 * 9e6);
  TableLaw tf = t;
  tf.operating_deflection.reset();
  tf.operating_force = 1e6 * 20e-6 + 2e11 * 400e-12;
  EXPECT_NEAR(LinearizeLaw(tf, "t").deflection, 20e-6, 1e-9);
}

TEST(Laws, AirFilmHertzChainMatchesIndependentSolution) {
  HertzLaw joint;
  joint.modulus = 5e9;  // soft (epoxy-like) contact so the joint compliance matters
  joint.radius = 3e-3;
  SeriesLaw chain{{Film(), joint}, 5e-6, std::nullopt};
  const SpringState st = LinearizeLaw(chain, "t");
  // Independent solution: Newton on the analytic functions, f(h) = h - s - d(W(h)) with
  // d(F) = (3F / (4 E' sqrt(R')))^(2/3).
  const double c = 4.0 / 3.0 * joint.modulus * std::sqrt(joint.radius);
  auto d_of = [&](double f) { return std::pow(f / c, 2.0 / 3.0); };
  double h = 5e-6;
  for (int i = 0; i < 100; ++i) {
    const double f = h - 5e-6 - d_of(W(h));
    const double df = 1.0 - (2.0 / 3.0) * std::pow(W(h) / c, -1.0 / 3.0) / c * DW(h);
    h -= f / df;
  }
  const double d = d_of(W(h));
  const double k_af = -DW(h), k_j = 2 * joint.modulus * std::sqrt(joint.radius * d);
  // Tolerances: the table interpolant reproduces W to ~1e-7 rel and W' to ~1e-5 rel.
  EXPECT_NEAR(st.gap, h, 1e-11);
  ASSERT_EQ(st.element_deflections.size(), 2u);
  EXPECT_NEAR(st.element_deflections[1], d, 1e-11);
  EXPECT_NEAR(st.force, W(h), 1e-5 * W(h));
  EXPECT_NEAR(st.stiffness, 1.0 / (1.0 / k_af + 1.0 / k_j), 1e-4 * st.stiffness);
  EXPECT_GT(h, 5e-6 + 1e-7) << "the joint compression must open the gap beyond the setting";
}

TEST(Laws, SeriesChainOnlyLowersStiffness) {
  // Thesis Table 8.1 in kind: air film alone at the setting (scheme A) > film in series with a
  // joint at the same gap (B) > equilibrium solve (C), which also opens the gap.
  HertzLaw joint;
  joint.modulus = 5e9;
  joint.radius = 3e-3;
  const double k_a = LinearizeLaw(Film(), "t").stiffness;
  joint.operating_force = W(5e-6);
  const double k_j = LinearizeLaw(joint, "t").stiffness;
  const double k_b = 1.0 / (1.0 / k_a + 1.0 / k_j);
  joint.operating_force.reset();
  const double k_c = LinearizeLaw(SeriesLaw{{Film(), joint}, 5e-6, std::nullopt}, "t").stiffness;
  EXPECT_GT(k_a, k_b);
  EXPECT_GT(k_b, k_c);
}

TEST(Laws, NonMonotoneLoadCurveIsInputError) {
  AirFilmLaw a = Film(5);
  a.load[3] = a.load[1];
  try {
    LinearizeLaw(a, "model.toml:12: spring 'B1'");
    FAIL();
  } catch (const InputError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("spring 'B1'"), std::string::npos) << m;
    EXPECT_NE(m.find("non-monotone"), std::string::npos) << m;
  }
}

TEST(Laws, ChainWithoutEquilibriumInRangeIsInputError) {
  HertzLaw joint;
  joint.modulus = 5e9;
  joint.radius = 3e-3;
  // Setting beyond the largest gap of the curve: no h in [1, 30] um satisfies the equilibrium.
  try {
    LinearizeLaw(SeriesLaw{{Film(), joint}, 40e-6, std::nullopt}, "model.toml:20: spring 'B2'");
    FAIL();
  } catch (const InputError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("spring 'B2'"), std::string::npos) << m;
    EXPECT_NE(m.find("no equilibrium"), std::string::npos) << m;
  }
}

}  // namespace
}  // namespace ema::model

// ---- micro_slip and laws in time (issue 14) ----
#include "ema/model/law_force.hpp"

namespace ema::model {
namespace {

TEST(MicroSlip, LinearisedStiffnessIsTheStuckStiffness) {
  const SpringState s = LinearizeLaw(Law(MicroSlipLaw{2.0e6, 5.0, 10}), "here");
  EXPECT_DOUBLE_EQ(s.stiffness, 2.0e6);
  EXPECT_FALSE(Law(MicroSlipLaw{2.0e6, 5.0, 1}).IsNonlinear());  // no operating point to set
  EXPECT_TRUE(Law(MicroSlipLaw{2.0e6, 5.0, 1}).IsNonlinearInTime());
  EXPECT_THROW(LinearizeLaw(Law(MicroSlipLaw{0.0, 5.0, 1}), "here"), InputError);
  EXPECT_THROW(LinearizeLaw(Law(MicroSlipLaw{1.0e6, -1.0, 1}), "here"), InputError);
}

TEST(MicroSlip, JenkinsLoopDissipatesFourFsTimesTheSlip) {
  // k = 1 N/um, Fs = 2 N: slips beyond 2 um. A cycle of amplitude 5 um: the loop is a
  // parallelogram of area 4 Fs (A - Fs/k) = 4 * 2 * 3e-6 = 24 uJ.
  const Law law(MicroSlipLaw{1.0e6, 2.0, 1});
  LawForce f(law, LinearizeLaw(law, "j"), 1e-5, 1.0, "j");
  EXPECT_DOUBLE_EQ(f.Force(1e-6), 1.0);  // stuck
  EXPECT_DOUBLE_EQ(f.Force(5e-6), 2.0);  // slipping: capped at Fs
  double work = 0.0, c_prev = 0.0, f_prev = 0.0;
  const int steps = 4000;
  for (int cycle = 0; cycle < 2; ++cycle)
    for (int i = 1; i <= steps; ++i) {
      const double c = 5e-6 * std::sin(kTwoPi * i / steps);
      const double force = f.Force(c);
      if (cycle == 1) work += 0.5 * (force + f_prev) * (c - c_prev);
      f.Commit(c);
      c_prev = c, f_prev = force;
    }
  EXPECT_NEAR(work, 24e-6, 0.01 * 24e-6);  // 1 %: trapezoidal work over 4000 steps
}

TEST(MicroSlip, IwanSlipsGraduallyAndReachesTheMacroSlipForce) {
  const Law law(MicroSlipLaw{1.0e6, 6.0, 50});
  LawForce f(law, LinearizeLaw(law, "j"), 1e-4, 1.0, "j");
  // u_max = 2 n Fs / (k (n + 1)) = 11.76 um; all elements slip beyond it: force = Fs.
  EXPECT_NEAR(f.Force(20e-6), 6.0, 1e-12);
  // At 1 um the first 4 elements (slip at 0.235 um steps) have slipped: force below k c.
  EXPECT_LT(f.Force(1e-6), 1.0);
  EXPECT_GT(f.Force(1e-6), 0.9);
  EXPECT_DOUBLE_EQ(f.Stiffness(), 1.0e6);
}

TEST(LawForce, HertzAndTableMatchTheirLinearisedStiffnessAtTheOperatingPoint) {
  HertzLaw h;
  h.modulus = 2e10;
  h.radius = 5e-3;
  h.operating_force = 50.0;
  const Law hertz(h);
  const SpringState hs = LinearizeLaw(hertz, "h");
  LawForce hf(hertz, hs, 1e-6, 1.0, "h");
  const double dc = 1e-10;
  EXPECT_NEAR((hf.Force(dc) - hf.Force(-dc)) / (2 * dc), hs.stiffness, 1e-5 * hs.stiffness);
  EXPECT_NEAR(hf.Force(-1.0), -50.0, 1e-9);  // contact lost: the preload is gone, nothing more
  TableLaw t;
  t.deflection = {0.0, 1e-6, 2e-6, 3e-6};
  t.force = {0.0, 10.0, 30.0, 60.0};
  t.operating_deflection = 1.5e-6;
  const Law table(t);
  const SpringState ts = LinearizeLaw(table, "t");
  LawForce tf(table, ts, 1.5e-6, 1.0, "t");
  // Tabulated on 801 points over ±1.5 um: the slope at 0 within 1 %.
  EXPECT_NEAR((tf.Force(5e-9) - tf.Force(-5e-9)) / 1e-8, ts.stiffness, 0.01 * ts.stiffness);
  EXPECT_NEAR(tf.Force(1.5e-6), 60.0 - ts.force, 1e-9);  // the grid ends on the table's last point
}

}  // namespace
}  // namespace ema::model
