// pipeline::FindingsOf: the first screen's numbers from a diagnosis — the springs' stiffness with
// rank 1's effect against the series-spring formula, the look-alike rule at its factor-20 edge,
// the verdict per test mode at 2σ and 3σ, each mode's share of the fall in χ², the misfit pattern.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "ema/formats/model_file.hpp"
#include "ema/model/effects.hpp"
#include "ema/model/solve.hpp"
#include "ema/pipeline/findings.hpp"

using ema::model::EffectTarget;

namespace ema::pipeline {
namespace {

diagnose::ModeComparison Mode(int m, double frequency_sigma, double shape_sigma, bool paired = true) {
  diagnose::ModeComparison c;
  c.test_mode = m;
  c.model_mode = paired ? m : -1;
  c.test_frequency_hz = 100.0 * (m + 1);
  c.sigma_hz = 0.1 * (m + 1);
  c.model_frequency_hz = paired ? c.test_frequency_hz + frequency_sigma * c.sigma_hz : kNaN;
  c.frequency_misfit_sigma = frequency_sigma;
  c.mac = paired ? 0.99 : kNaN;
  c.shape_misfit_sigma = shape_sigma;
  return c;
}

diagnose::Candidate Reading(int rank, const std::string& kind, const EffectTarget& target, double probability) {
  diagnose::Candidate c;
  c.rank = rank;
  c.kind = kind;
  c.target = model::TargetText(target);
  c.probability = probability;
  if (const model::EffectKindInfo* info = model::FindEffectKind(kind)) {  // "none": the model as given
    model::Effect e;
    e.kind = info->kind;
    e.target = target;
    c.effects = {e};
  }
  return c;
}

TEST(Findings, SpringsOfRankOnesComplianceFollowTheSeriesFormula) {
  // The benchmark's two-body stack with a compliance of 2 N/µm in series with every mount: each
  // mount spring's linearised stiffness becomes k k_e / (k + k_e), and the element alone is k_e.
  const model::Model nominal =
      formats::ReadModelFile(std::filesystem::path(EMA_SOURCE_DIR) / "tests/diagnose/data/benchmark-stack2.toml");
  const double k_e = 2e6;
  diagnose::Diagnosis d;
  d.candidates = {Reading(1, "series_compliance", EffectTarget::Named("mounts"), 0.9),
                  Reading(2, "none", EffectTarget(), 0.1)};
  d.candidates[0].effects[0].parameters["k"] = k_e;
  diagnose::FittedParameter p;
  p.effect_kind = model::EffectKind::kSeriesCompliance;
  p.target = EffectTarget::Named("mounts");
  p.name = "k";
  p.value = k_e;
  p.sigma = 1e5;
  d.candidates[0].parameters = {p};
  d.candidates[0].modes = {Mode(0, 0.5, 0.2)};
  d.baseline = d.candidates[1];
  d.baseline.modes = {Mode(0, 40.0, 1.0)};
  d.effect_probabilities = {{model::EffectKind::kSeriesCompliance, EffectTarget::Named("mounts"), 0.9}};
  const Findings f = FindingsOf(d, nominal);
  ASSERT_EQ(f.effects.size(), 1u);
  EXPECT_DOUBLE_EQ(f.effects[0].probability, 0.9);
  EXPECT_FALSE(f.effects[0].wildcard);  // a whole group: no wildcard of its own
  ASSERT_EQ(f.effects[0].parameters.size(), 1u);
  ASSERT_EQ(f.effects[0].springs.size(), 1u);
  const model::Solution before = model::Solve(nominal, {});
  double expected = 0.0;
  const std::vector<int> mounts = model::TargetSprings(nominal, EffectTarget::Named("mounts"));
  for (int i : mounts) {
    const double k = before.springs[static_cast<std::size_t>(i)].stiffness;
    expected += k * k_e / (k + k_e);
  }
  expected /= static_cast<double>(mounts.size());
  EXPECT_NEAR(f.effects[0].springs[0].per_spring_n_per_m, expected, 1e-9 * expected);
  EXPECT_NEAR(f.effects[0].springs[0].element_n_per_m, k_e, 1e-9 * k_e);
  // The single mode carries the whole fall in χ²: (40² + 1²) − (0.5² + 0.2²) of it.
  ASSERT_EQ(f.modes.size(), 1u);
  EXPECT_DOUBLE_EQ(f.modes[0].share_pct, 100.0);
  EXPECT_EQ(f.modes[0].verdict, ModeVerdict::kWithinNoise);
}

TEST(Findings, LookAlikesWithinAFactor20AndVerdictsAt2And3Sigma) {
  diagnose::Diagnosis d;
  // Rank 1 at 0.5; a group of 3 readings on points summed to 0.5 + 0.03; one reading at
  // 0.5/20 × 1.01 (in) and one at 0.5/20 × 0.99 (out).
  d.candidates = {Reading(1, "added_mass", EffectTarget::Points({101}), 0.5),
                  Reading(2, "added_mass", EffectTarget::Points({102}), 0.02),
                  Reading(3, "added_mass", EffectTarget::Points({103}), 0.01),
                  Reading(4, "stiffness_scale", EffectTarget::Named("joints"), 0.5 / 20 * 1.01),
                  Reading(5, "mass_scale", EffectTarget::Named("top"), 0.5 / 20 * 0.99),
                  Reading(6, "none", EffectTarget(), 0.0)};
  d.candidates[0].noise_consistent = false;
  d.candidates[0].reduced_chi2 = 12.0;
  d.candidates[0].modes = {Mode(0, 1.0, 0.5), Mode(1, 2.5, 0.1), Mode(2, -1.5, 3.5), Mode(3, 0.0, 0.0, false)};
  d.candidates[0].model_error.frequency_rel = 0.01;  // the shared part (0) below each mode's
  d.baseline = d.candidates[5];
  d.baseline.modes = {Mode(0, 3.0, 0.5), Mode(1, 4.0, 0.1), Mode(2, -1.5, 3.5), Mode(3, 0.0, 0.0, false)};
  d.groups = {{"added_mass", "points:*", {1, 2, 3}, 0.53},
              {"stiffness_scale", "joints", {4}, 0.5 / 20 * 1.01},
              {"mass_scale", "top", {5}, 0.5 / 20 * 0.99},
              {"none", "", {6}, 0.0}};
  d.effect_probabilities = {{model::EffectKind::kAddedMass, EffectTarget::EveryPoint(), 0.53},
                            {model::EffectKind::kAddedMass, EffectTarget::Points({101}), 0.5}};
  const Findings f = FindingsOf(d, model::Model());
  ASSERT_EQ(f.lookalikes.size(), 2u);
  EXPECT_TRUE(f.lookalikes[0].holds_rank_one);
  EXPECT_EQ(f.lookalikes[0].readings, 2);
  EXPECT_NEAR(f.lookalikes[0].probability, 0.03, 1e-15);
  EXPECT_EQ(f.lookalikes[0].span, GroupSpan::kPoints);
  EXPECT_EQ(f.lookalikes[1].kind, "stiffness_scale");
  EXPECT_FALSE(f.lookalikes[1].holds_rank_one);
  EXPECT_EQ(f.effects[0].wildcard, EffectTarget::EveryPoint());
  EXPECT_DOUBLE_EQ(f.effects[0].wildcard_probability, 0.53);
  // Verdicts: 1σ within noise, 2.5σ marginal, 3.5σ in shape a misfit, unpaired.
  ASSERT_EQ(f.modes.size(), 4u);
  EXPECT_EQ(f.modes[0].verdict, ModeVerdict::kWithinNoise);
  EXPECT_EQ(f.modes[1].verdict, ModeVerdict::kMarginal);
  EXPECT_EQ(f.modes[2].verdict, ModeVerdict::kMisfit);
  EXPECT_EQ(f.modes[3].verdict, ModeVerdict::kUnpaired);
  // The fall in χ²: mode 1 9 − 1 = 8, mode 2 16 − 6.25 = 9.75, mode 3 nothing.
  EXPECT_NEAR(f.modes[0].share_pct, 100.0 * 8.0 / 17.75, 1e-12);
  EXPECT_NEAR(f.modes[1].share_pct, 100.0 * 9.75 / 17.75, 1e-12);
  EXPECT_NEAR(f.modes[2].share_pct, 0.0, 1e-12);
  // Not adequate, but the model's own error does not dominate: no "outside the vocabulary".
  EXPECT_FALSE(f.adequate);
  EXPECT_FALSE(f.model_inadequate);
  // The worst modes first: mode 3 (3.8σ), then 2 (2.5σ), then 1 (1.1σ).
  ASSERT_EQ(f.worst_modes.size(), 3u);
  EXPECT_EQ(f.worst_modes[0], 2);
  EXPECT_EQ(f.worst_modes[1], 1);
  EXPECT_EQ(f.worst_modes[2], 0);
  // Paired modes off both ways by more than 1σ (+2.5 and −1.5): distributed differently.
  EXPECT_FALSE(f.pattern.all_one_way);
  EXPECT_TRUE(f.pattern.mixed);
  EXPECT_TRUE(f.pattern.shapes_off_more);  // shapes 0.5² + 0.1² + 3.5² against 1 + 6.25 + 2.25
  EXPECT_TRUE(f.pattern.unpaired_modes);
}

TEST(Findings, AReadingTheModelsOwnErrorAlsoExplainsIsNamedBesideNone) {
  // Form-rich benchmark case 31's numbers: a 4.4 % all-points mass hidden, rank 1 the model as
  // given at 84.3 % with an inferred error of 3.5 % shared by all frequencies, the all-points mass
  // next at 13.9 % bringing the mean frequency error from 4.32 % to 0.92 %.
  // Rank 2 moves the three modes by −2 %, −1.75 % and −2.33 % (a uniform shift: within a factor
  // 2 of each other); `next_shifts` replaces that.
  auto diagnosis = [](double p_next, double error_next, std::vector<double> next_shifts = {-0.02, -0.0175, -0.07 / 3}) {
    diagnose::Diagnosis d;
    d.candidates = {Reading(1, "none", EffectTarget(), 0.843), Reading(2, "added_mass", EffectTarget::AllPoints(), p_next),
                    Reading(3, "added_mass", EffectTarget::Points({103}), 0.1)};
    for (diagnose::Candidate& c : d.candidates) {
      c.noise_consistent = false, c.model_error.dominates = true;
      for (int m = 0; m < 3; ++m) c.modes.push_back(Mode(m, 40.0, 0.2));
    }
    for (int m = 0; m < 3; ++m) {
      d.candidates[1].modes[m].model_frequency_hz *= 1.0 + next_shifts[m];
      d.candidates[2].modes[m].model_frequency_hz *= 1.0 - 0.02;  // rank 3 uniform too: never looked at
    }
    d.candidates[0].mean_abs_frequency_error_pct = 4.32;
    d.candidates[0].model_error.frequency_rel = 0.0063;
    d.candidates[0].model_error.frequency_common_rel = 0.035;
    d.candidates[1].mean_abs_frequency_error_pct = error_next;
    d.candidates[1].model_error.frequency_rel = 0.0021;
    d.candidates[1].effects[0].parameters["mass"] = 0.0576;
    d.candidates[2].mean_abs_frequency_error_pct = 0.5;
    return d;
  };
  const Findings f = FindingsOf(diagnosis(0.139, 0.92), model::Model());
  ASSERT_TRUE(f.model_inadequate);
  ASSERT_TRUE(f.model_error_lookalike.has_value());
  EXPECT_EQ(f.model_error_lookalike->rank, 2);
  EXPECT_DOUBLE_EQ(f.model_error_lookalike->probability, 0.139);
  EXPECT_DOUBLE_EQ(f.model_error_lookalike->error_after_pct, 0.92);
  EXPECT_DOUBLE_EQ(f.model_error_lookalike->model_error.frequency_rel, 0.0021);
  EXPECT_EQ(f.model_error_lookalike->description, "an added mass of 57.6 g per point at all_points");
  // Exactly half the error away still counts; a little less does not.
  EXPECT_TRUE(FindingsOf(diagnosis(0.139, 2.16), model::Model()).model_error_lookalike.has_value());
  EXPECT_FALSE(FindingsOf(diagnosis(0.139, 2.17), model::Model()).model_error_lookalike.has_value());
  // The look-alike rule's factor-20 edge (0.843 / 20 = 0.04215) — and only the next reading is
  // looked at, never rank 3 behind it (which would qualify on its own numbers).
  EXPECT_TRUE(FindingsOf(diagnosis(0.0422, 0.92), model::Model()).model_error_lookalike.has_value());
  EXPECT_FALSE(FindingsOf(diagnosis(0.0421, 0.92), model::Model()).model_error_lookalike.has_value());
  // Up to twice as far is alike (1.99×); a reading that moves one mode 2.1× another, or one the
  // other way, or leaves one where it was (a point mass at a node of that mode) is not the shared
  // error's pattern.
  EXPECT_TRUE(FindingsOf(diagnosis(0.139, 0.92, {-0.01, -0.0199, -0.015}), model::Model()).model_error_lookalike.has_value());
  EXPECT_FALSE(FindingsOf(diagnosis(0.139, 0.92, {-0.01, -0.021, -0.015}), model::Model()).model_error_lookalike.has_value());
  EXPECT_FALSE(FindingsOf(diagnosis(0.139, 0.92, {-0.02, 0.02, -0.02}), model::Model()).model_error_lookalike.has_value());
  EXPECT_FALSE(FindingsOf(diagnosis(0.139, 0.92, {-0.02, 0.0, -0.02}), model::Model()).model_error_lookalike.has_value());
  // A model adequate to the noise, or rank 1 with effects: nothing to say.
  diagnose::Diagnosis adequate = diagnosis(0.139, 0.92);
  adequate.candidates[0].noise_consistent = true;
  EXPECT_FALSE(FindingsOf(adequate, model::Model()).model_error_lookalike.has_value());
  diagnose::Diagnosis effects_first = diagnosis(0.139, 0.92);
  std::swap(effects_first.candidates[0], effects_first.candidates[1]);
  EXPECT_FALSE(FindingsOf(effects_first, model::Model()).model_error_lookalike.has_value());
}

}  // namespace
}  // namespace ema::pipeline
