// How the diagnosis weighs test shapes that a hammer test cannot measure cleanly, and the swap
// move of its search (all three found by the diagnosis benchmark, docs/diagnosis-benchmark.md):
//  - a complex shape (MPC < 1: a pole fitted as a blend of two modes, or polluted by noise) is
//    weighed by its own 1 − MPC, not as a 1 % shape;
//  - two model modes closer than the half-power width ζ·f are one subspace to a hammer test: a
//    test shape that is any blend of them is judged against their span.
//  - a best set holding a look-alike of a true effect is swapped toward the truth.
// Before this, spurious member effects were "found" that rotate the model's modes toward the
// polluted test shapes (rank 1 = the true effect + two member factors of 0.91–1.11). Each test
// fails without its fix.
//
// The articles: a nearly symmetric table (Ixx ≈ Iyy, lateral mounts 1 % apart) on four corner
// mounts, so its two rocking pairs are repeated roots to within 0.5 %; the truth is the mounts
// 40 % softer (a group effect that keeps the symmetry); and a three-body stack from the benchmark.
// Test frequencies carry 0.1 % noise and shapes 1 % (fixed seeds), as in diagnose_test.cpp.
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <filesystem>
#include <random>

#include "ema/diagnose/diagnose.hpp"
#include "ema/formats/model_file.hpp"
#include "ema/formats/io.hpp"
#include "ema/model/effects.hpp"
#include "ema/model/solve.hpp"

using ema::model::EffectTarget;

namespace ema::diagnose {
namespace {

namespace fs = std::filesystem;

using model::Anchor;
using model::EffectKind;
using model::Model;

Model Table() {
  Model m;
  m.name = "nearly symmetric table";
  m.origin = "table (built in code)";
  model::Body top;
  top.name = "table";
  top.mass = 10.0;
  top.inertia = Eigen::Vector3d(0.20, 0.201, 0.35);
  top.uncertainty = 0.02;
  m.bodies = {top};
  int j = 0;
  for (double x : {-0.2, 0.2})
    for (double y : {-0.2, 0.2}) {
      ++j;
      const double k[] = {2.0e6, 2.02e6, 5.0e6};
      for (int d = 0; d < 3; ++d) {
        model::Spring s;
        s.name = "M" + std::to_string(j) + "XYZ"[d];
        s.group = "mounts";
        s.member = "M" + std::to_string(j);
        s.a = Anchor{"table", 0, Eigen::Vector3d(x, y, -0.05), true};
        s.b = Anchor{model::kGround, 0, Eigen::Vector3d(x, y, -0.05), true};
        s.direction = Eigen::Vector3d::Unit(d);
        s.law = model::Law(model::LinearLaw{k[d]});
        m.springs.push_back(s);
      }
    }
  int id = 1;
  for (double x : {-0.2, 0.2})
    for (double y : {-0.2, 0.2}) m.points.push_back({id++, Anchor{"table", 0, Eigen::Vector3d(x, y, 0.05), true}, 0});
  m.damping.ratio = 0.01;
  return m;
}

ModeSet Noisy(const Model& truth, unsigned seed) {
  ModeSet modes = model::Solve(truth, {}).modes;
  std::mt19937 rng(seed);
  std::normal_distribution<double> g;
  for (Mode& mode : modes.modes) {
    mode.frequency_hz *= 1.0 + 1e-3 * g(rng);
    const double rms = std::sqrt(mode.shape.squaredNorm() / mode.shape.size());
    for (Eigen::Index i = 0; i < mode.shape.size(); ++i) mode.shape(i) += 1e-2 * rms * std::complex<double>(g(rng), g(rng));
  }
  modes.source = "synthetic table test";
  return modes;
}

// Index pairs of modes closer than 1 % (the table's repeated roots).
std::vector<std::pair<int, int>> ClosePairs(const ModeSet& modes) {
  std::vector<std::pair<int, int>> pairs;
  for (size_t a = 0; a + 1 < modes.modes.size(); ++a)
    if (modes.modes[a + 1].frequency_hz / modes.modes[a].frequency_hz - 1.0 < 0.01)
      pairs.push_back({static_cast<int>(a), static_cast<int>(a + 1)});
  return pairs;
}

void ExpectTheTruthAlone(const Diagnosis& d) {
  ASSERT_FALSE(d.candidates.empty());
  const Candidate& first = d.candidates.front();
  EXPECT_EQ(first.kind, "stiffness_scale") << d.explanation;
  EXPECT_EQ(first.target, "mounts") << d.explanation;
  ASSERT_EQ(first.parameters.size(), 1u) << d.explanation;
  // 0.1 % frequency noise on six modes: the factor lands within ~1 %; 5 % as in the other tests.
  EXPECT_NEAR(first.parameters.front().value / 0.6, 1.0, 0.05) << d.explanation;
  EXPECT_GT(first.probability, 0.5) << d.explanation;
}

TEST(TestModeQuality, BlendsOfRepeatedRootsAreJudgedAgainstTheirSpan) {
  const Model nominal = Table();
  const Model truth = model::ApplyEffect(
      nominal, {EffectKind::kStiffnessScale, EffectTarget::Named("mounts"), {{"factor", 0.6}}, std::nullopt, 0});
  ModeSet test = Noisy(truth, 11);
  const auto pairs = ClosePairs(test);
  ASSERT_GE(pairs.size(), 1u) << "the table must have a repeated root for this test";
  // A hammer test returns some basis of each repeated root's plane: rotate every pair by 35°.
  const double c = std::cos(35.0 * M_PI / 180.0), s = std::sin(35.0 * M_PI / 180.0);
  for (const auto& [a, b] : pairs) {
    const Eigen::VectorXcd pa = test.modes[a].shape, pb = test.modes[b].shape;
    test.modes[a].shape = c * pa + s * pb;
    test.modes[b].shape = -s * pa + c * pb;
  }
  ExpectTheTruthAlone(Diagnose(nominal, {{"", test}}));
}

TEST(TestModeQuality, AComplexShapeDoesNotBuySpuriousEffects) {
  // Case 12 of the diagnosis benchmark: a three-body stack whose middle body has a spring to
  // ground (3.83 N/µm). Its first two modes are 1.4 % apart; the test fits them as ONE complex
  // mode (the first polluted by the second, out of phase: MPC 0.8 and 0.6), as the chain did at
  // 2 % noise. Weighed as a 1 % shape, that mode bought a second ground spring (on the base).
  const fs::path file = fs::path(EMA_SOURCE_DIR) / "tests/diagnose/data/benchmark-stack3.toml";
  const Model nominal = formats::ReadModelFile(file);
  const Model truth = model::ApplyEffect(
      nominal,
      {EffectKind::kGroundSpring, EffectTarget::Named("middle"), {{"k", 3826524.5447497265}}, std::nullopt, 0});
  const ModeSet clean = Noisy(truth, 12);
  ASSERT_GE(clean.modes.size(), 8u);
  ASSERT_LT(clean.modes[1].frequency_hz / clean.modes[0].frequency_hz - 1.0, 0.02);
  for (double amount : {0.5, 0.8}) {
    ModeSet test = clean;
    test.modes[0].shape += std::complex<double>(0.0, amount) * test.modes[1].shape *
                           (test.modes[0].shape.norm() / test.modes[1].shape.norm());
    test.modes.erase(test.modes.begin() + 1);
    const Diagnosis d = Diagnose(nominal, {{"", test}});
    ASSERT_FALSE(d.candidates.empty());
    const Candidate& first = d.candidates.front();
    EXPECT_EQ(first.kind, "ground_spring") << amount << ": " << d.explanation;
    EXPECT_EQ(first.target, "middle") << amount << ": " << d.explanation;
    ASSERT_EQ(first.parameters.size(), 1u) << d.explanation;
    EXPECT_NEAR(first.parameters.front().value / 3826524.5447497265, 1.0, 0.05) << d.explanation;
  }
}

TEST(SearchSwap, ALookAlikeInTheBestSetIsSwappedForTheTruth) {
  // Case 39 of the diagnosis benchmark: a two-body stack whose base has a spring to ground
  // (3.75 N/µm) and a 0.54 kg mass at point 104. Forward selection reaches "a mass on all points
  // + a mass at point 101 + the ground spring" and the backward check, which only drops effects,
  // keeps it (with options.swaps = false that is rank 1); swapping the all-points mass for its
  // look-alikes and dropping the rest finds the truth.
  const fs::path file = fs::path(EMA_SOURCE_DIR) / "tests/diagnose/data/benchmark-stack2.toml";
  const Model nominal = formats::ReadModelFile(file);
  Model truth = model::ApplyEffect(
      nominal, {EffectKind::kGroundSpring, EffectTarget::Named("base"), {{"k", 3750979.8508189674}}, std::nullopt, 0});
  truth = model::ApplyEffect(
      truth, {EffectKind::kAddedMass, EffectTarget::Points({104}), {{"mass", 0.542521313540122}}, std::nullopt, 0});
  const Diagnosis d = Diagnose(nominal, {{"", Noisy(truth, 1)}});
  ASSERT_FALSE(d.candidates.empty());
  const Candidate& first = d.candidates.front();
  EXPECT_EQ(first.kind, "added_mass+ground_spring") << d.explanation;
  EXPECT_EQ(first.target, "points:104+base") << d.explanation;
  for (const FittedParameter& p : first.parameters) {
    // 0.1 % frequency noise: within 10 % (the benchmark's tolerance) with room to spare.
    const double want = p.effect_kind == EffectKind::kGroundSpring ? 3750979.8508189674 : 0.542521313540122;
    EXPECT_NEAR(p.value / want, 1.0, 0.10) << model::KindName(p.effect_kind) << " " << d.explanation;
  }
}

// Case 43 of the diagnosis benchmark (seed 2026), its files as the chain wrote them: a footbridge
// frame built from parts (252 DOFs, so searched through reduced models), cross-beam zone X1 2.47×
// stiffer than modelled and 41.5 kg at point 2013; the modes are what `ema fit` found in its
// simulated hammer test (2 % noise). The search's best pair was {deck ×1.36, point 2013}: the deck
// plate spans the same cross positions as both cross-beam zones and stood in for X1 at a value
// X1 itself does not fit, so the true pair was never fitted and three effects won ({deck, a 8.7 kg
// and a 163 kg point mass} at 92 %). Fails with polish_swaps = 0 (the best full-solve fit of each
// size has each effect swapped for its look-alikes, each screened for its own value) and when FE
// parts are not look-alikes of each other (both 2026-11-26).
TEST(SearchSwap, ADeckFactorStandingInForOneCrossBeamZoneIsSwappedForTheTruth) {
  const fs::path folder = fs::path(EMA_SOURCE_DIR) / "tests/diagnose/data/benchmark-parts43";
  const Model nominal = formats::ReadModelFile(folder / "model.toml");
  const ModeSet test = formats::ReadModeSet(folder / "modes.unv");
  const Diagnosis d = Diagnose(nominal, {{"", test}});
  ASSERT_FALSE(d.candidates.empty());
  const Candidate& first = d.candidates.front();
  EXPECT_EQ(first.kind, "stiffness_scale+added_mass") << d.explanation;
  EXPECT_EQ(first.target, "cross/X1+points:2013") << d.explanation;
  ASSERT_EQ(first.parameters.size(), 2u) << d.explanation;
  for (const FittedParameter& p : first.parameters) {
    // 2 % response noise through the whole chain: the fit gives 2.464 and 41.39 kg (σ 1 %); the
    // benchmark's 10 % would let a look-alike's value through, 2 % does not.
    const double want = p.effect_kind == EffectKind::kStiffnessScale ? 2.473290338261697 : 41.471351752140485;
    EXPECT_NEAR(p.value / want, 1.0, 0.02) << model::KindName(p.effect_kind) << " " << d.explanation;
  }
  EXPECT_GT(first.probability, 0.9) << d.explanation;
}

}  // namespace
}  // namespace ema::diagnose
