// Model error in the likelihood (docs/diagnose.md "Model error"): truths the model's vocabulary
// cannot express. The two-body stack of the diagnosis benchmark (tests/diagnose/data) with every
// one of its 24 joint and mount springs off by its own factor — a scatter no set of up to three
// effects can express — and no discrete effect hidden.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "ema/diagnose/diagnose.hpp"
#include "ema/model/effects.hpp"
#include "ema/model/solve.hpp"
#include "stack_truths.hpp"

using ema::model::EffectTarget;

namespace ema::diagnose {
namespace model_error_test {
using model::EffectKind;
using model::Model;

using test::Measured;
using test::Scattered;
using test::SpreadMass;
using test::Stack;

// The model error's known size: the rms relative frequency error of the nominal model against
// the (noise-free) truth, mode by mode in frequency order.
double RmsFrequencyError(const Model& nominal, const Model& truth) {
  const ModeSet a = model::Solve(nominal, {}).modes, b = model::Solve(truth, {}).modes;
  double sum = 0.0;
  const size_t n = std::min(a.modes.size(), b.modes.size());
  for (size_t i = 0; i < n; ++i) sum += std::pow(b.modes[i].frequency_hz / a.modes[i].frequency_hz - 1.0, 2);
  return std::sqrt(sum / static_cast<double>(n));
}

bool HasMassEffect(const Candidate& c) {
  for (const auto& e : c.effects)
    if (e.kind == EffectKind::kAddedMass || e.kind == EffectKind::kMassScale) return true;
  return false;
}

TEST(ModelError, InferredScaleMatchesAKnownScatterAndNoMassIsInvented) {
  // Monte Carlo over 4 seeds, 3 % spring scatter (the modes move by about 0.5 %, five times the
  // test's σ). Each time: the model error the "none" reading infers is within a factor 2 of the
  // truth's rms frequency error (its grid steps by 1.65×, and rms vs 1σ of a Gaussian over 12
  // modes differ by up to ~30 %) and is said to dominate the test's σ; the masses — weighed,
  // exact in the truth — are rarely invented: a mass must explain the data beyond what the model
  // error explains. With the model's form taken as exact (model_error = false) the scales are
  // not inferred at all and seed 4 is answered with an invented mass (this test fails there).
  const Model nominal = Stack();
  DiagnoseOptions options;
  options.max_effects = 2;
  int invented = 0;
  for (unsigned seed = 1; seed <= 4; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    const Model truth = Scattered(nominal, 0.03, seed);
    const double known = RmsFrequencyError(nominal, truth);
    const Diagnosis d = Diagnose(nominal, {{"", Measured(truth, seed)}}, options);
    ASSERT_FALSE(d.candidates.empty());
    const Candidate& none = d.baseline;
    EXPECT_GT(none.model_error.frequency_rel, known / 2.0) << "known " << known;
    EXPECT_LT(none.model_error.frequency_rel, known * 2.0) << "known " << known;
    EXPECT_TRUE(none.model_error.dominates);
    const Candidate& first = d.candidates.front();
    if (HasMassEffect(first)) ++invented;
    // Honest: a reading that leaves the model inadequate is not certain.
    if (!first.noise_consistent) {
      EXPECT_TRUE(first.model_error.dominates) << d.explanation;
    }
    // Seed 4: the model as given must win. With the form taken as exact, rank 1 was "joints/J1
    // ×1.04 + 42.5 g at point 101" at 98.6 % (2026-11-26).
    if (seed == 4) {
      EXPECT_EQ(first.kind, "none") << d.explanation;
    }
  }
  // With the form taken as exact, 2 of these 4 seeds put an invented mass at rank 1 (42 % and
  // 98.6 %); with the model error, seed 3 alone: its scatter looks like 54 g at point 202 (the
  // mass explains 78 % of the misfit, a genuine look-alike of this scatter on 12 modes).
  EXPECT_LE(invented, 1);
}

TEST(ModelError, AMassSpreadOverTheBodiesIsTheModelsErrorNotAnAddedMass) {
  // Monte Carlo over 6 seeds: every body 1.2 % heavier than the model says (mass and inertia —
  // a spread non-structural mass, painted and cabled, which no added mass at a point expresses)
  // and every spring off by 1 % of its own: each mode ~0.6 % low, all of them together. That is
  // one error shared by the modes (docs/diagnose.md "Model error": a shift common to all), not
  // six independent ones a mass at one point "explains". Before the shared term and the prior
  // odds per effect (2026-11-27) rank 1 was an added mass at a point in 2 of these 6 seeds (and
  // "none" inferred no shared scale at all); then in none of them, and since the shapes weigh per
  // DOF in at most one (below).
  const Model nominal = Stack();
  DiagnoseOptions options;
  options.max_effects = 2;
  int invented = 0;
  for (unsigned seed = 11; seed <= 16; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    Model truth = Scattered(nominal, 0.01, seed);
    SpreadMass(&truth, 1.012);
    const Diagnosis d = Diagnose(nominal, {{"", Measured(truth, seed)}}, options);
    ASSERT_FALSE(d.candidates.empty());
    const Candidate& first = d.candidates.front();
    bool point_mass = false;
    for (const auto& e : first.effects)
      point_mass = point_mass || (e.kind == EffectKind::kAddedMass && e.target != EffectTarget::AllPoints());
    if (point_mass) {
      ++invented;
      // Honest when it happens: a look-alike of the scatter, never a certainty.
      EXPECT_LT(first.probability, 0.9) << d.explanation;
    }
    // The shared error is what the model lacks: "none" says it (its common scale near the 0.6 %
    // shift, within the grid's step of 2.4×).
    EXPECT_GT(d.baseline.model_error.frequency_common_rel, 0.002) << d.explanation;
    EXPECT_LT(d.baseline.model_error.frequency_common_rel, 0.03) << d.explanation;
  }
  // With the shapes per DOF (2026-11-27) seed 11 is the one: its spring scatter mixes the two
  // highest modes (1.93 and 2.03 kHz, 7 % rms off at the 24 DOFs) as a mass at point 204 would,
  // and that mass is rank 1 at 0.72. With a 5 % shape floor instead of 10 %, three of six.
  EXPECT_LE(invented, 1);
}

TEST(ModelError, ExactFormKeepsTheExactAnswer) {
  // The nominal stack with one mount 40 % softer and nothing else: the model's form is exact,
  // so the inferred model error is negligible (below the test's σ) and rank 1 is the mount, as
  // without model error.
  const Model nominal = Stack();
  const Model truth = model::ApplyEffect(
      nominal,
      {EffectKind::kStiffnessScale, EffectTarget::MemberOf("mounts", "M2"), {{"factor", 0.6}}, std::nullopt, 0});
  DiagnoseOptions options;
  options.max_effects = 1;
  const Diagnosis d = Diagnose(nominal, {{"", Measured(truth, 7)}}, options);
  ASSERT_FALSE(d.candidates.empty());
  const Candidate& first = d.candidates.front();
  EXPECT_EQ(first.target, "mounts/M2") << d.explanation;
  EXPECT_FALSE(first.model_error.dominates) << d.explanation;
  EXPECT_TRUE(first.noise_consistent) << d.explanation;
  EXPECT_GT(first.probability, 0.9) << d.explanation;
}

TEST(ModelError, TwoTestsOfOneSetupCountTheModelsErrorOnce) {
  // Two tests of one setup (a repeat, a follow-up test) see the model's error of each mode once:
  // the structure and its model are the same in both, only the noise differs. Weighed by the
  // frequencies alone (the shapes' floor at 1000 %: their floor is a measurement σ, new in each
  // test, and would count again rightly), the stack with 3 % spring scatter and nothing hidden,
  // six seeds: the best reading with an effect stands as far behind "none" with the test twice, or
  // with a second test of new noise, as with the test alone — measured within 0.03 nats for the
  // copy, 0.4 for the new draw. With an error per test mode (before 2026-12-07) the copy's
  // evidence for the effect grew by up to 3.1 nats, and in seed 3 the two tests put an invented
  // 54 g at point 202 at rank 1 (0.3 nats ahead of "none", 1.5 behind with one test).
  const Model nominal = Stack();
  DiagnoseOptions options;
  options.max_effects = 1;
  options.shape_dof_sigma = 10.0;
  auto best_effect = [](const Diagnosis& d) {
    for (const Candidate& c : d.candidates)
      if (!c.effects.empty()) return c.log_evidence - d.baseline.log_evidence;
    return -std::numeric_limits<double>::infinity();
  };
  for (unsigned seed = 1; seed <= 6; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    const Model truth = Scattered(nominal, 0.03, seed);
    const ModeSet test = Measured(truth, seed);
    const Diagnosis one = Diagnose(nominal, {{"", test}}, options);
    const Diagnosis copy = Diagnose(nominal, {{"", test}, {"", test}}, options);
    const Diagnosis two = Diagnose(nominal, {{"", test}, {"", Measured(truth, seed + 100)}}, options);
    ASSERT_FALSE(one.candidates.empty());
    ASSERT_FALSE(copy.candidates.empty());
    ASSERT_FALSE(two.candidates.empty());
    EXPECT_NEAR(best_effect(copy), best_effect(one), 0.1) << copy.explanation;
    EXPECT_NEAR(best_effect(two), best_effect(one), 1.0) << two.explanation;
    EXPECT_TRUE(two.candidates.front().effects.empty()) << two.explanation;
    // The model error inferred from both is the one test's (the grid's own point or its neighbour).
    EXPECT_LT(std::abs(std::log(two.baseline.model_error.frequency_rel / one.baseline.model_error.frequency_rel)), 0.6);
  }
}

}  // namespace model_error_test
}  // namespace ema::diagnose
