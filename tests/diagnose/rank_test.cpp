// The ranking of evaluated candidates (diagnose/src/explain.cpp Rank): probabilities from the
// scores, and the rule that a far reading leaving the model inadequate is listed below a plausible
// reading of similar fit — similar by the frequencies' misfit *and* within a factor 20 in evidence
// (docs/diagnose.md "Model error"; the form-rich benchmark's cases 6, 7, 61 had the truth demoted
// below a reading 10⁻¹² as likely).
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "../diagnose/src/internal.hpp"

namespace ema::diagnose {
namespace {

model::Effect Stiffness(const std::string& group, const std::string& member) {
  model::Effect e;
  e.kind = model::EffectKind::kStiffnessScale;
  e.target = member.empty() ? model::EffectTarget::Named(group) : model::EffectTarget::MemberOf(group, member);
  return e;
}

Candidate Reading(model::Effect effect, double score, double reduced_chi2, bool far) {
  Candidate c;
  c.effects = {std::move(effect)};
  c.kind = "stiffness_scale";
  c.target = model::TargetText(c.effects.front().target);
  c.score = score;
  c.cost = reduced_chi2;
  c.reduced_chi2 = reduced_chi2;
  c.noise_consistent = false;
  FittedParameter p;
  p.outside_prior = far;
  c.parameters = {p};
  c.residuals = Eigen::VectorXd::Zero(3);
  return c;
}

// Benchmark case 7 of the form-rich family, its numbers: the support S1 nearly lost (×0.0018,
// 12.6σ of its stated 50 %) at score 72.55, reduced χ² 340; "the supports × 0.553" at 126.30, χ² 200.
std::vector<Candidate> Case7(double plausible_score) {
  Candidate none;
  none.kind = "none";
  none.score = 200.0;
  none.reduced_chi2 = 2000.0;
  none.residuals = Eigen::VectorXd::Zero(3);
  std::vector<Candidate> all = {Reading(Stiffness("supports", "S1"), 72.55, 340.4, true),
                                Reading(Stiffness("supports", ""), plausible_score, 200.4, false), none};
  all[0].residuals << 1.0, 0.0, 0.0;
  all[1].residuals << 0.0, 1.0, 0.0;
  return all;
}

TEST(Rank, AFarReadingTheEvidenceFavoursByFarStaysRankOne) {
  std::vector<Candidate> all = Case7(126.30);
  const Candidate none = all.back();
  detail::Rank(&all, none);
  ASSERT_EQ(all.size(), 3u);
  EXPECT_EQ(all[0].target, "supports/S1");
  EXPECT_EQ(all[0].rank, 1);
  // exp(−(126.30 − 72.55)/2) = 2.1·10⁻¹²: the plausible reading is no rival.
  EXPECT_NEAR(all[0].probability, 1.0, 1e-9);
  EXPECT_NEAR(all[1].probability, std::exp(-0.5 * (126.30 - 72.55)), 1e-15);
  for (const std::string& flag : all[0].flags) EXPECT_EQ(flag.find("listed below"), std::string::npos) << flag;
}

TEST(Rank, AFarReadingIsListedBelowAPlausibleOneOfSimilarFit) {
  // The plausible reading 4 score units behind (a factor e² = 7.4 < 20): similar fit.
  std::vector<Candidate> all = Case7(76.55);
  const Candidate none = all.back();
  detail::Rank(&all, none);
  EXPECT_EQ(all[0].target, "supports");
  EXPECT_EQ(all[1].target, "supports/S1");
  EXPECT_EQ(all[1].rank, 2);
  ASSERT_FALSE(all[1].flags.empty());
  EXPECT_NE(all[1].flags.back().find("listed below stiffness_scale of 'supports'"), std::string::npos)
      << all[1].flags.back();
  // The probabilities are the evidence's, whatever the order: 1 / (1 + e⁻²) for the far one.
  EXPECT_NEAR(all[1].probability, 1.0 / (1.0 + std::exp(-2.0)), 1e-6);
}

TEST(Rank, TheFactorTwentyIsTheEdge) {
  // 2 ln 20 = 5.99: just inside demotes, just outside does not.
  std::vector<Candidate> inside = Case7(72.55 + 5.9);
  std::vector<Candidate> outside = Case7(72.55 + 6.1);
  const Candidate none = inside.back();
  detail::Rank(&inside, none);
  detail::Rank(&outside, none);
  EXPECT_EQ(inside[0].target, "supports");
  EXPECT_EQ(outside[0].target, "supports/S1");
}

}  // namespace
}  // namespace ema::diagnose
