// Data-quality checks (frf/quality.hpp) against FRF sets with known truth: exact pole-residue
// FRFs of a 4-DOF structure (tests/curvefit/synthetic.hpp), then one defect built in on purpose.
#include <gtest/gtest.h>

#include <cmath>

#include "curvefit/synthetic.hpp"
#include "ema/core/error.hpp"
#include "ema/frf/quality.hpp"

namespace ema::frf {
namespace {

using curvefit::test::MakeFrfSet;
using curvefit::test::MakeTruth;

// Three well-separated modes (40, 95, 160 Hz, 1-2 % damping), references at DOFs 1 and 3:
// H(3/1) and H(1/3) both exist, 1 and 3 are driving points.
FrfSet TwoReferenceSet() {
  const auto truth = MakeTruth({40.0, 95.0, 160.0}, {0.01, 0.015, 0.02}, 4);
  return MakeFrfSet(truth, {0, 2}, 200.0, 0.5, 0.0, 1);
}

TEST(Quality, ReciprocalPairEqualPassesAndTenPercentOffWarns) {
  FrfSet set = TwoReferenceSet();
  auto report = CheckFrfQuality({set});
  ASSERT_EQ(report.reciprocity.size(), 1u);
  const auto& ok = report.reciprocity[0];
  EXPECT_EQ(ok.dof_i, (Dof{1, 3}));
  EXPECT_EQ(ok.dof_j, (Dof{3, 3}));
  EXPECT_LT(ok.relative_difference, 1e-12);  // exact FRFs: equal to rounding
  EXPECT_EQ(ok.verdict, Verdict::kPass);

  // H(3/1) (reference 1 = block 0, output 3 = column 2) made 10 % too large: a calibration error.
  set.h[0].col(2) *= 1.1;
  report = CheckFrfQuality({set});
  ASSERT_EQ(report.reciprocity.size(), 1u);
  const auto& off = report.reciprocity[0];
  // ||a - 1.1 a|| / (0.5 (||a|| + 1.1 ||a||)) = 0.1 / 1.05 exactly; the tolerance is rounding.
  EXPECT_NEAR(off.relative_difference, 0.1 / 1.05, 1e-12);
  EXPECT_NEAR(off.amplitude_ratio, 1.0 / 1.1, 1e-12);  // ||H_13|| / ||H_31||
  EXPECT_EQ(off.verdict, Verdict::kWarn);
  EXPECT_NE(off.reason.find("9.5 %"), std::string::npos) << off.reason;
  EXPECT_EQ(report.Overall(), Verdict::kWarn);
}

TEST(Quality, RovingHammerAgainstRovingSensorFiles) {
  const auto truth = MakeTruth({40.0, 95.0, 160.0}, {0.01, 0.015, 0.02}, 4);
  // Roving sensor: hammer at 1, all four DOFs measured.
  const FrfSet sensor = MakeFrfSet(truth, {0}, 200.0, 0.5, 0.0, 1);
  // Roving hammer: one sensor at 1, hammer at all four DOFs (outputs and references swapped).
  const FrfSet all = MakeFrfSet(truth, {0, 1, 2, 3}, 200.0, 0.5, 0.0, 2);
  FrfSet hammer;
  hammer.frequency_hz = all.frequency_hz;
  hammer.outputs = {{1, 3}};
  hammer.references = all.outputs;
  hammer.roving_hammer = true;
  for (int r = 0; r < 4; ++r) hammer.h.push_back(all.h[r].col(0));
  const auto report = CheckFrfQuality({sensor, hammer}, {}, {"sensor.unv", "hammer.unv"});
  ASSERT_EQ(report.reciprocity.size(), 3u);  // H(1/k) against H(k/1), k = 2..4
  for (const auto& c : report.reciprocity) {
    EXPECT_LT(c.relative_difference, 1e-12);
    EXPECT_EQ(c.verdict, Verdict::kPass);
  }
  ASSERT_EQ(report.driving_points.size(), 1u);  // H(1/1) in both files, checked once

  // A different frequency grid cannot be compared line by line.
  FrfSet coarse = hammer;
  coarse.frequency_hz *= 1.01;
  EXPECT_THROW(CheckFrfQuality({sensor, coarse}, {}, {"sensor.unv", "hammer.unv"}), InputError);
}

TEST(Quality, DrivingPointWithInvertedSensorWarns) {
  FrfSet set = TwoReferenceSet();
  auto report = CheckFrfQuality({set});
  ASSERT_EQ(report.driving_points.size(), 2u);  // 1/1 and 3/3
  for (const auto& c : report.driving_points) {
    EXPECT_EQ(c.resonances, 3) << c.reason;  // the three modes peak in both driving points
    EXPECT_EQ(c.flipped, 0);
    // Passive accelerance: Im >= 0 at every line, so the weighted sign is +1 to rounding.
    EXPECT_NEAR(c.sign_consistency, 1.0, 1e-12);
    EXPECT_EQ(c.verdict, Verdict::kPass);
  }
  set.h[0].col(0) *= -1.0;  // driving point 1/1 with an inverted sensor
  report = CheckFrfQuality({set});
  ASSERT_EQ(report.driving_points.size(), 2u);
  const auto& bad = report.driving_points[0];
  EXPECT_EQ(bad.dof, (Dof{1, 3}));
  EXPECT_EQ(bad.flipped, 3);
  EXPECT_NEAR(bad.sign_consistency, -1.0, 1e-12);
  EXPECT_EQ(bad.verdict, Verdict::kWarn);
  EXPECT_NE(bad.reason.find("inverted"), std::string::npos) << bad.reason;
  ASSERT_EQ(bad.flipped_frequencies_hz.size(), 3u);
  EXPECT_NEAR(bad.flipped_frequencies_hz[0], 40.0, 0.5);  // the peak line of mode 1 (0.5 Hz spacing)
  EXPECT_EQ(report.driving_points[1].verdict, Verdict::kPass);

  // The same inverted FRF labelled with the sensor's true direction (-Z) is consistent again.
  set.outputs[0] = {1, -3};
  report = CheckFrfQuality({set});
  // Output 1-Z and reference 1+Z are now one DOF (sign folded in): a driving point that passes.
  ASSERT_FALSE(report.driving_points.empty());
  EXPECT_EQ(report.driving_points[0].dof, (Dof{1, 3}));
  EXPECT_EQ(report.driving_points[0].verdict, Verdict::kPass);
}

TEST(Quality, MobilityAndReceptanceDrivingPointsUseTheirOwnSign) {
  const auto truth = MakeTruth({40.0, 95.0}, {0.01, 0.02}, 3);
  for (int k_pow : {0, 1}) {
    FrfSet set = MakeFrfSet(truth, {0}, 150.0, 0.5, 0.0, 3, k_pow);
    auto report = CheckFrfQuality({set});
    ASSERT_EQ(report.driving_points.size(), 1u);
    EXPECT_EQ(report.driving_points[0].verdict, Verdict::kPass) << report.driving_points[0].reason;
    set.h[0].col(0) *= -1.0;
    report = CheckFrfQuality({set});
    EXPECT_EQ(report.driving_points[0].verdict, Verdict::kWarn) << "k_pow " << k_pow;
  }
}

TEST(Quality, CoherenceMapAndScatterFromCoherenceAndAverages) {
  FrfSet set = TwoReferenceSet();
  const int n = set.LineCount();
  set.coherence.assign(2, Eigen::MatrixXd::Constant(n, 4, 0.95));
  set.averages = Eigen::MatrixXi::Constant(2, 4, 5);
  // FRF 2/1: coherence 0.5 on the first 30 % of the lines (a loose sensor at low frequency).
  const int low = static_cast<int>(0.3 * n);
  set.coherence[0].col(1).head(low).setConstant(0.5);
  // FRF 4/3: a single impact at coherence 0.8: eps = sqrt(0.2) / (sqrt(0.8) sqrt(2)) = 0.354.
  set.coherence[1].col(3).setConstant(0.8);
  set.averages(1, 3) = 1;
  const auto report = CheckFrfQuality({set});
  ASSERT_TRUE(report.has_coherence);
  ASSERT_EQ(report.frfs.size(), 8u);
  // Map: 8 FRFs × the band lines (all but DC), rows in reference-then-output order.
  EXPECT_EQ(report.coherence_map.coherence.rows(), 8);
  EXPECT_EQ(report.coherence_map.coherence.cols(), n - 1);
  EXPECT_EQ(report.coherence_map.labels[1], "2+Z/1+Z");
  EXPECT_EQ(report.coherence_map.coherence(1, 0), 0.5);
  EXPECT_EQ(report.coherence_map.coherence(1, n - 2), 0.95);

  const auto& good = report.frfs[0];
  EXPECT_NEAR(good.mean_coherence, 0.95, 1e-12);  // a sum of ~400 equal terms: rounding
  EXPECT_EQ(good.low_coherence_fraction, 0.0);
  EXPECT_EQ(good.averages, 5);
  // sqrt(0.05) / (sqrt(0.95) sqrt(10)) = 0.072548..., the same at every line.
  EXPECT_NEAR(good.median_random_error, std::sqrt(0.05) / (std::sqrt(0.95) * std::sqrt(10.0)), 1e-15);
  EXPECT_EQ(good.coherence_verdict, Verdict::kPass);
  EXPECT_EQ(good.scatter_verdict, Verdict::kPass);

  const auto& loose = report.frfs[1];
  EXPECT_NEAR(loose.low_coherence_fraction, (low - 1.0) / (n - 1.0), 1e-12);  // DC is not in the band
  EXPECT_EQ(loose.coherence_verdict, Verdict::kWarn);

  const auto& single = report.frfs[7];
  EXPECT_EQ(single.response, (Dof{4, 3}));
  EXPECT_NEAR(single.median_random_error, std::sqrt(0.2) / (std::sqrt(0.8) * std::sqrt(2.0)), 1e-15);
  EXPECT_EQ(single.scatter_verdict, Verdict::kWarn);
  EXPECT_EQ(single.coherence_verdict, Verdict::kWarn);  // 0.8 < 0.9 on every line
}

TEST(Quality, RandomErrorMatchesBendatPiersol) {
  // eps = sqrt(1-g2)/(sqrt(g2) sqrt(2n)): g2 = 0.5 gives 1/sqrt(2n): 0.5 for n = 2, 1/sqrt(2) for n = 1.
  EXPECT_DOUBLE_EQ(RandomErrorOfMagnitude(0.5, 2), 0.5);
  EXPECT_DOUBLE_EQ(RandomErrorOfMagnitude(0.5, 1), std::sqrt(0.5));
  EXPECT_DOUBLE_EQ(RandomErrorOfMagnitude(1.0, 3), 0.0);
  EXPECT_TRUE(std::isnan(RandomErrorOfMagnitude(0.0, 3)));
  EXPECT_TRUE(std::isnan(RandomErrorOfMagnitude(0.9, 0)));
}

TEST(Quality, OptionsAreValidated) {
  QualityOptions o;
  std::string error;
  EXPECT_TRUE(o.IsValid(&error));
  o.reciprocity_tolerance = 0.0;
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_NE(error.find("reciprocity_tolerance"), std::string::npos);
  EXPECT_THROW(CheckFrfQuality({TwoReferenceSet()}, o), InputError);
}

}  // namespace
}  // namespace ema::frf
