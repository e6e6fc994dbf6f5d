// Missing-effect diagnosis on "test" modes made from the model plus one known effect plus noise.
//
// The model is a small aerostatic-guideway-like article built in code: a carriage floating on
// air-film pads (series chains with an air film, operated by a stud setting) over a base plate
// that sits on linear mounts. Test data = the model with a known effect, solved, with 0.1 %
// (1σ) noise on every frequency and 1 % of the RMS amplitude on every shape value (complex),
// from fixed seeds: the accuracy of a good hammer test. Tolerances: fitted parameter within 5 %
// of the truth (issue 7); with this noise the fits land within about 1 %.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "ema/core/error.hpp"
#include "ema/diagnose/diagnose.hpp"
#include "ema/model/effects.hpp"
#include "ema/model/solve.hpp"

using ema::model::EffectTarget;

namespace ema::diagnose {
namespace {

using model::Anchor;
using model::Effect;
using model::EffectKind;
using model::Law;
using model::LinearLaw;
using model::Model;
using model::Spring;

// Load-lift curve W(h) of one pad: exponential (vertical pads) or inverse-square (lateral pads),
// so a change of gap changes vertical and lateral stiffness in different ratios.
model::AirFilmLaw Film(bool exponential, double scale) {
  model::AirFilmLaw film;
  for (int i = 0; i <= 80; ++i) {
    const double h = (0.5 + 0.75 * i) * 1e-6;
    film.gap.push_back(h);
    film.load.push_back(exponential ? scale * 300.0 * std::exp(-h / 6e-6) : scale * 80.0 * std::pow(5e-6 / h, 2.0));
  }
  film.operating_gap = 5e-6;
  return film;
}

Law FilmChain(bool exponential, double scale, double setting) {
  model::SeriesLaw chain;
  chain.elements.push_back(Law(Film(exponential, scale)));
  chain.setting = setting;
  return Law(chain);
}

Spring MakeSpring(const std::string& name, const std::string& group, const std::string& a, const std::string& b,
                  Eigen::Vector3d at, Eigen::Vector3d dir, Law law) {
  Spring s;
  s.name = name;
  s.group = group;
  s.a = Anchor{a, 0, at, true};
  s.b = Anchor{b, 0, at, true};
  s.direction = dir;
  s.law = std::move(law);
  return s;
}

// lateral_group: the group of the lateral pads ("bearings" mixes pad kinds; another name leaves
// the "bearings" group with four identical vertical pads).
Model Guideway(const std::string& lateral_group = "bearings") {
  Model m;
  m.name = "test guideway";
  m.origin = "guideway (built in code)";
  model::Body carriage{"carriage", 2.88, {0.0117763, 0.0151621, 0.0104617}, Eigen::Vector3d::Zero(),
                       Eigen::Vector3d::Zero(), 0};
  model::Body base{"base", 12.0, {0.08, 0.10, 0.15}, Eigen::Vector3d::Zero(), Eigen::Vector3d(0, 0, -0.08), 0};
  m.bodies = {carriage, base};
  int n = 0;
  for (double x : {-0.06, 0.06})
    for (double y : {-0.03, 0.03})
      m.springs.push_back(MakeSpring("V" + std::to_string(++n), "bearings", "carriage", "base", {x, y, -0.03},
                                     Eigen::Vector3d::UnitZ(), FilmChain(true, 1.0, 5e-6)));
  for (double x : {-0.06, 0.06})
    for (double y : {-0.045, 0.045})
      m.springs.push_back(MakeSpring("L" + std::to_string(++n), lateral_group, "carriage", "base", {x, y, 0.0},
                                     Eigen::Vector3d(0, y > 0 ? -1.0 : 1.0, 0), FilmChain(false, 1.0, 5e-6)));
  m.springs.push_back(
      MakeSpring("drive", "drive", "carriage", "base", {0, 0, 0}, Eigen::Vector3d::UnitX(), Law(LinearLaw{3e6})));
  for (double x : {-0.1, 0.1})
    for (double y : {-0.08, 0.08}) {
      m.springs.push_back(MakeSpring("MZ" + std::to_string(++n), "mounts", "base", model::kGround, {x, y, -0.1},
                                     Eigen::Vector3d::UnitZ(), Law(LinearLaw{8e6})));
      m.springs.push_back(MakeSpring("MX" + std::to_string(n), "mounts", "base", model::kGround, {x, y, -0.1},
                                     Eigen::Vector3d::UnitX(), Law(LinearLaw{2e6 + 1e6 * (x > 0)})));
      m.springs.push_back(MakeSpring("MY" + std::to_string(n), "mounts", "base", model::kGround, {x, y, -0.1},
                                     Eigen::Vector3d::UnitY(), Law(LinearLaw{3e6})));
    }
  int id = 101;
  for (double x : {-0.06, 0.06})
    for (double y : {-0.03, 0.03}) m.points.push_back({id++, Anchor{"carriage", 0, {x, y, 0.03}, true}, 0});
  id = 201;
  for (double x : {-0.1, 0.1})
    for (double y : {-0.08, 0.08}) m.points.push_back({id++, Anchor{"base", 0, {x, y, -0.06}, true}, 0});
  m.damping.ratio = 0.01;
  m.setups = {{"stud-5um", {{"bearings", 5e-6}}, 0}, {"stud-9um", {{"bearings", 9e-6}}, 0}};
  return m;
}

// The "test": truth model solved, noise on frequencies and shapes (fixed seed).
ModeSet NoisyTest(const Model& truth, const std::string& setup, unsigned seed, double frequency_noise = 1e-3,
                  double shape_noise = 1e-2) {
  model::SolveOptions so;
  so.setup = setup;
  ModeSet modes = model::Solve(truth, so).modes;
  std::mt19937 rng(seed);
  std::normal_distribution<double> g;
  for (Mode& mode : modes.modes) {
    mode.frequency_hz *= 1.0 + frequency_noise * g(rng);
    const double rms = std::sqrt(mode.shape.squaredNorm() / mode.shape.size());
    for (Eigen::Index i = 0; i < mode.shape.size(); ++i)
      mode.shape(i) += shape_noise * rms * std::complex<double>(g(rng), g(rng));
    mode.pole = FrequencyAndDampingToPole(mode.frequency_hz, mode.damping_ratio);
  }
  modes.source = "synthetic test [" + setup + "]";
  return modes;
}

// True when `c` is the one effect `kind` on `target`.
bool IsSingle(const Candidate& c, EffectKind kind, const EffectTarget& target) {
  return c.effects.size() == 1 && c.effects[0].kind == kind && c.effects[0].target == target;
}

double FittedValue(const Candidate& c, const std::string& name) {
  for (const FittedParameter& p : c.parameters)
    if (p.name == name) return p.value;
  return kNaN;
}

struct KindCase {
  Effect truth;
  std::string parameter;
  double value;
  bool two_setups;
};

class EachKind : public ::testing::TestWithParam<KindCase> {};

TEST_P(EachKind, RanksFirstWithItsParameter) {
  const KindCase& kc = GetParam();
  const Model nominal = Guideway();
  const Model truth = model::ApplyEffect(nominal, kc.truth);
  std::vector<SetupModes> tests;
  if (kc.two_setups) {
    tests.push_back({"stud-5um", NoisyTest(truth, "stud-5um", 1)});
    tests.push_back({"stud-9um", NoisyTest(truth, "stud-9um", 2)});
  } else {
    tests.push_back({"", NoisyTest(truth, "", 3)});
  }
  DiagnoseOptions options;
  options.max_effects = 1;  // singles only: fast, and this test is about the single ranking
  const Diagnosis d = Diagnose(nominal, tests, options);
  ASSERT_FALSE(d.candidates.empty());
  const Candidate& first = d.candidates.front();
  EXPECT_EQ(first.kind, model::KindName(kc.truth.kind)) << d.explanation;
  ASSERT_EQ(first.effects.size(), 1u) << d.explanation;
  EXPECT_EQ(first.effects[0].target, kc.truth.target) << d.explanation;
  EXPECT_NEAR(FittedValue(first, kc.parameter) / kc.value, 1.0, 0.05) << d.explanation;
  // The posterior σ is finite and small: 0.1 % frequency noise on 12 modes pins one parameter
  // to well under 5 %; the truth lies within 4σ of the fit (σ from the Laplace posterior).
  const FittedParameter& p = first.parameters.front();
  ASSERT_TRUE(std::isfinite(p.sigma));
  EXPECT_LT(p.sigma / p.value, 0.05);
  EXPECT_LT(std::abs(p.value - kc.value), 4.0 * p.sigma + 0.01 * kc.value);
  // The true effect explains nearly all of the baseline residual (the rest is the noise).
  EXPECT_GT(first.explained_pct, 95.0);
  EXPECT_LT(first.mean_abs_frequency_error_pct, 0.5);
}

Effect Make(EffectKind kind, const EffectTarget& target, const std::string& key, double value) {
  Effect e{kind, target, {{key, value}}, std::nullopt, 0};
  if (kind == EffectKind::kSeriesCompliance) {
    e.parameters.clear();
    e.law = Law(LinearLaw{value});
  }
  return e;
}

INSTANTIATE_TEST_SUITE_P(
    Diagnose, EachKind,
    ::testing::Values(
        KindCase{Make(EffectKind::kSeriesCompliance, EffectTarget::Named("bearings"), "k", 6.5e6), "k", 6.5e6, true},
        KindCase{Make(EffectKind::kStiffnessScale, EffectTarget::Named("mounts"), "factor", 0.6), "factor", 0.6, false},
        KindCase{Make(EffectKind::kOperatingPoint, EffectTarget::Named("bearings"), "value", 7.5e-6), "value", 7.5e-6,
                 false},
        KindCase{Make(EffectKind::kAddedMass, EffectTarget::AllPoints(), "mass", 0.03), "mass", 0.03, false},
        KindCase{Make(EffectKind::kMassScale, EffectTarget::Named("carriage"), "factor", 1.3), "factor", 1.3, false},
        KindCase{Make(EffectKind::kGroundSpring, EffectTarget::Named("carriage"), "k", 2e6), "k", 2e6, false}),
    [](const auto& info) { return model::KindName(info.param.truth.kind); });

TEST(Diagnose, PosteriorSigmaMatchesTheMonteCarloSpread) {
  // 40 noise realisations (fixed seeds) of the mounts 40 % softer, 0.1 % frequency noise — the
  // same as the σ floor the residuals are weighted with, so the Laplace posterior σ should be the
  // estimator's real scatter. Checked: the median reported σ against the standard deviation of
  // the 40 fitted factors within ±35 % (the sample std of 40 values is itself uncertain by
  // ~11 %, and the Laplace σ is a local approximation), and no bias beyond 3 standard errors.
  const Model nominal = Guideway();
  const Model truth =
      model::ApplyEffect(nominal, Make(EffectKind::kStiffnessScale, EffectTarget::Named("mounts"), "factor", 0.6));
  DiagnoseOptions options;
  options.max_effects = 1;
  options.members = false;
  std::vector<double> values, sigmas;
  for (unsigned seed = 100; seed < 140; ++seed) {
    const Diagnosis d = Diagnose(nominal, {{"", NoisyTest(truth, "", seed)}}, options);
    for (const Candidate& c : d.candidates)
      if (IsSingle(c, EffectKind::kStiffnessScale, EffectTarget::Named("mounts"))) {
        values.push_back(c.parameters.front().value);
        sigmas.push_back(c.parameters.front().sigma);
        break;
      }
  }
  ASSERT_EQ(values.size(), 40u);
  double mean = 0.0;
  for (double v : values) mean += v / values.size();
  double var = 0.0;
  for (double v : values) var += (v - mean) * (v - mean) / (values.size() - 1);
  const double spread = std::sqrt(var);
  std::sort(sigmas.begin(), sigmas.end());
  const double median_sigma = 0.5 * (sigmas[19] + sigmas[20]);
  EXPECT_NEAR(median_sigma / spread, 1.0, 0.35) << "median σ " << median_sigma << ", Monte Carlo spread " << spread;
  EXPECT_LT(std::abs(mean - 0.6), 3.0 * spread / std::sqrt(40.0)) << "mean " << mean;
}

TEST(Diagnose, NoEffectRanksNoneFirst) {
  const Model nominal = Guideway();
  std::vector<SetupModes> tests = {{"stud-5um", NoisyTest(nominal, "stud-5um", 21)},
                                   {"stud-9um", NoisyTest(nominal, "stud-9um", 22)}};
  DiagnoseOptions options;
  const Diagnosis d = Diagnose(nominal, tests, options);
  EXPECT_EQ(d.candidates.front().kind, "none") << d.explanation;
  EXPECT_NE(d.explanation.find("No candidate effect"), std::string::npos);
  // 0.1 % noise at a 0.1 % floor: "none" is clearly the most probable reading.
  EXPECT_GT(d.candidates.front().probability, 0.5) << d.explanation;
  double sum = 0.0;
  for (const Candidate& c : d.candidates) sum += c.probability;
  EXPECT_NEAR(sum, 1.0, 1e-12);
}

TEST(Diagnose, TwoSetupsSeparateSeriesComplianceFromStiffnessScale) {
  // "bearings" = four identical vertical pads: with one setup a series compliance is exactly a
  // uniform stiffness factor on them; with two stud settings the compliance's share differs
  // (the film is stiffer at 5 µm than at 9 µm, and the gap shifts by a different amount).
  const Model nominal = Guideway("lateral");
  const Effect truth_effect = Make(EffectKind::kSeriesCompliance, EffectTarget::Named("bearings"), "k", 6.5e6);
  const Model truth = model::ApplyEffect(nominal, truth_effect);
  DiagnoseOptions options;
  options.max_effects = 1;

  const Diagnosis one = Diagnose(nominal, {{"stud-5um", NoisyTest(truth, "stud-5um", 31)}}, options);
  // One setup: the data cannot separate the readings (equal misfit, flagged as tied with rank 1);
  // the priors order them (a soft series element is likelier than a factor-4 stiffness error).
  const Candidate& a = one.candidates[0];
  EXPECT_EQ(a.kind, "series_compliance") << one.explanation;
  EXPECT_EQ(a.target, "bearings");
  bool found = false;
  for (const Candidate& c : one.candidates)
    if (IsSingle(c, EffectKind::kStiffnessScale, EffectTarget::Named("bearings"))) {
      found = true;
      EXPECT_LT(std::abs(c.cost - a.cost), 1.0);  // same misfit within noise (cost is a χ²)
    }
  EXPECT_TRUE(found);
  EXPECT_NE(std::find(a.tied_with.begin(), a.tied_with.end(), "stiffness_scale of 'bearings'"), a.tied_with.end())
      << one.explanation;

  const Diagnosis two = Diagnose(
      nominal, {{"stud-5um", NoisyTest(truth, "stud-5um", 31)}, {"stud-9um", NoisyTest(truth, "stud-9um", 32)}},
      options);
  const Candidate& best = two.candidates[0];
  EXPECT_EQ(best.kind, "series_compliance") << two.explanation;
  EXPECT_EQ(best.target, "bearings");
  EXPECT_NEAR(FittedValue(best, "k") / 6.5e6, 1.0, 0.05);
  // The stiffness scale now pays for not fitting both settings: well behind (> 10 in BIC,
  // "very strong" evidence).
  for (const Candidate& c : two.candidates)
    if (IsSingle(c, EffectKind::kStiffnessScale, EffectTarget::Named("bearings"))) {
      EXPECT_GT(c.score - best.score, 10.0);
    }
  EXPECT_TRUE(best.tied_with.empty()) << two.explanation;
}

TEST(Diagnose, PairReportedOnlyWhenItBeatsTheBestSingle) {
  // Truth with two effects: a pair must win; with one effect, no pair may be reported above it.
  Model nominal = Guideway();
  nominal.bodies[0].uncertainty = 0.5;  // an unweighed carriage: a 30 % mass error is plausible
  Model truth =
      model::ApplyEffect(nominal, Make(EffectKind::kMassScale, EffectTarget::Named("carriage"), "factor", 1.3));
  truth = model::ApplyEffect(truth, Make(EffectKind::kStiffnessScale, EffectTarget::Named("mounts"), "factor", 0.6));
  const Diagnosis d = Diagnose(nominal, {{"", NoisyTest(truth, "", 41)}}, DiagnoseOptions{});
  const Candidate& first = d.candidates.front();
  ASSERT_EQ(first.effects.size(), 2u) << d.explanation;
  // Order of effects in a combination: the candidate list's order (spring groups before bodies).
  EXPECT_EQ(first.kind, "stiffness_scale+mass_scale") << d.explanation;
  EXPECT_EQ(first.target, "mounts+carriage") << d.explanation;
  for (const Candidate& c : d.candidates) {
    if (c.effects.size() != 1) continue;
    EXPECT_GT(c.score, first.score);
  }
  ASSERT_EQ(first.parameters.size(), 2u);
  // 0.1 % frequency noise: both factors land within 1 %; 5 % is the tolerance.
  EXPECT_EQ(first.parameters[0].effect_kind, EffectKind::kStiffnessScale);
  EXPECT_NEAR(first.parameters[0].value, 0.6, 0.05 * 0.6);
  EXPECT_EQ(first.parameters[1].effect_kind, EffectKind::kMassScale);
  EXPECT_NEAR(first.parameters[1].value, 1.3, 0.05 * 1.3);
  EXPECT_GT(first.probability, 0.5);
}

TEST(Diagnose, PoorlyMeasuredModeWeighsLess) {
  // One test mode 3 % off (a badly fitted pole). When the fit says so (its frequency spread is
  // 3 % of f), that mode's residual is divided by its σ and barely pulls the fit; without the
  // spread it counts like every other mode and biases the factor.
  const Model nominal = Guideway();
  const Model truth =
      model::ApplyEffect(nominal, Make(EffectKind::kStiffnessScale, EffectTarget::Named("mounts"), "factor", 0.6));
  ModeSet test = NoisyTest(truth, "", 61, 2e-4, 1e-2);
  test.modes[0].frequency_hz *= 1.03;
  DiagnoseOptions options;
  options.max_effects = 1;
  options.members = false;
  const Diagnosis unweighted = Diagnose(nominal, {{"", test}}, options);
  test.modes[0].frequency_spread_hz = 0.03 * test.modes[0].frequency_hz;
  const Diagnosis weighted = Diagnose(nominal, {{"", test}}, options);
  ASSERT_EQ(weighted.candidates.front().kind, "stiffness_scale") << weighted.explanation;
  ASSERT_EQ(weighted.candidates.front().target, "mounts") << weighted.explanation;
  const double with_sigma = FittedValue(weighted.candidates.front(), "factor");
  // 0.02 % noise on 11 good modes: within 1 % of the truth once the bad mode is down-weighted.
  EXPECT_NEAR(with_sigma / 0.6, 1.0, 0.01);
  double without_sigma = kNaN;
  for (const Candidate& c : unweighted.candidates)
    if (IsSingle(c, EffectKind::kStiffnessScale, EffectTarget::Named("mounts")))
      without_sigma = FittedValue(c, "factor");
  ASSERT_TRUE(std::isfinite(without_sigma));
  EXPECT_LT(std::abs(with_sigma - 0.6), std::abs(without_sigma - 0.6));
}

TEST(DiagnoseOptions, DefaultsAreValidAndBadValuesAreNamed) {
  std::string why;
  EXPECT_TRUE(DiagnoseOptions{}.IsValid(&why)) << why;
  DiagnoseOptions o;
  o.max_effects = 4;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("max_effects"), std::string::npos) << why;
  o = DiagnoseOptions{};
  o.frequency_floor = 0.0;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("frequency_floor"), std::string::npos) << why;
  Criterion c = Criterion::kBic;
  EXPECT_TRUE(StringToCriterion("evidence", &c));
  EXPECT_EQ(c, Criterion::kEvidence);
  EXPECT_EQ(CriterionToString(Criterion::kAicc), "aicc");
  EXPECT_FALSE(StringToCriterion("nonsense", &c));
  // Diagnose refuses invalid options as a usage error.
  EXPECT_THROW(Diagnose(Guideway(), {{"", NoisyTest(Guideway(), "", 5)}}, o), UsageError);
}

TEST(Diagnose, BadInput) {
  const Model nominal = Guideway();
  ModeSet test = NoisyTest(nominal, "", 5);
  // A setup the model lacks.
  EXPECT_THROW(Diagnose(nominal, {{"stud-7um", test}}), InputError);
  // Test points the model does not define.
  ModeSet foreign = test;
  for (Dof& d : foreign.dofs) d.node += 1000;
  EXPECT_THROW(Diagnose(nominal, {{"", foreign}}), InputError);
  // No modes.
  ModeSet empty = test;
  empty.modes.clear();
  EXPECT_THROW(Diagnose(nominal, {{"", empty}}), InputError);
  // Too few paired modes: one mode only.
  ModeSet single = test;
  single.modes.resize(1);
  try {
    Diagnose(nominal, {{"", single}});
    ADD_FAILURE() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("paired"), std::string::npos) << e.what();
  }
}

TEST(Diagnose, PriorPullsTheFitTowardsTheModel) {
  // The base really is 4 % heavier. Declared as weighed to 0.5 % (uncertainty), the MAP fit of
  // mass_scale must sit closer to 1 than with a loose prior (0.5 = "known to a factor 1.5"): the
  // prior is part of the objective, not only of the evidence.
  Model nominal = Guideway();
  model::Effect truth_effect;
  truth_effect.kind = EffectKind::kMassScale;
  truth_effect.target = EffectTarget::Named("base");
  truth_effect.parameters["factor"] = 1.04;
  const Model truth = model::ApplyEffect(nominal, truth_effect);
  const std::vector<SetupModes> tests = {{"stud-5um", NoisyTest(truth, "stud-5um", 11, 3e-4, 3e-3)},
                                         {"stud-9um", NoisyTest(truth, "stud-9um", 12, 3e-4, 3e-3)}};
  DiagnoseOptions options;
  options.max_effects = 1;
  double sigma_data = kNaN;
  auto fitted = [&](double uncertainty, Diagnosis* out) {
    Model m = nominal;
    for (auto& b : m.bodies)
      if (b.name == "base") b.uncertainty = uncertainty;
    *out = Diagnose(m, tests, options);
    for (const Candidate& c : out->candidates)
      if (IsSingle(c, EffectKind::kMassScale, EffectTarget::Named("base"))) {
        if (uncertainty > 0.1) sigma_data = c.parameters.front().sigma;
        return FittedValue(c, "factor");
      }
    return kNaN;
  };
  Diagnosis loose, tight;
  const double f_loose = fitted(0.5, &loose), f_tight = fitted(0.005, &tight);
  ASSERT_TRUE(std::isfinite(f_loose) && std::isfinite(f_tight) && std::isfinite(sigma_data));
  EXPECT_NEAR(f_loose, 1.04, 0.01) << loose.explanation;  // the data's own answer
  // Gaussian data (σ_d from the loose fit's posterior) times a Gaussian prior N(1, 0.005²): the
  // MAP is the precision-weighted mean. Within a quarter of the pull (the likelihood is only
  // locally Gaussian); a fit that ignores the prior stays at the data's answer and fails.
  const double wd = 1.0 / (sigma_data * sigma_data), wp = 1.0 / (0.005 * 0.005);
  const double expected = (f_loose * wd + 1.0 * wp) / (wd + wp);
  EXPECT_NEAR(f_tight, expected, 0.25 * (f_loose - expected)) << "σ_d " << sigma_data << ", loose " << f_loose;
}

// The guideway with its four mounts as members MA..MD, MB's springs rated to 0.1 %
// (uncertainty 0.001), and both setups' noisy test modes of MB really 1.3× stiffer.
std::pair<Model, std::vector<SetupModes>> MountMBStifferThanItsRating() {
  Model nominal = Guideway();
  for (Spring& s : nominal.springs) {
    if (s.group != "mounts") continue;
    const double x = s.a.at.x(), y = s.a.at.y();
    s.member = x < 0 ? (y > 0 ? "MB" : "MA") : (y > 0 ? "MD" : "MC");
    if (s.member == "MB") s.uncertainty = 0.001;
  }
  const Model truth = model::ApplyEffect(
      nominal, Make(EffectKind::kStiffnessScale, EffectTarget::MemberOf("mounts", "MB"), "factor", 1.3));
  return {nominal, {{"stud-5um", NoisyTest(truth, "stud-5um", 31)}, {"stud-9um", NoisyTest(truth, "stud-9um", 32)}}};
}

TEST(Diagnose, MemberFitsGoToThePlausibleMembers) {
  // Mount "MB" (the base's mount at x = −0.1, y = +0.08) really is 1.3 times stiffer, but the
  // engineer declares its springs known to 0.1 % (uncertainty 0.001: ln 1.3 = 262 σ, a prior
  // cost of 3.4e4 against a data misfit of about 2e3 at the nominal model). With a budget of
  // one member fit, the screening must rank members by the MAP objective (misfit + prior), as
  // the evidence will: one of the other three mounts gets the fit (no other kind on a member can
  // stiffen a mount) and MB, implausible at any factor that explains the data, gets none.
  // Ranked by misfit alone, MB (exact) would take the only fit and no plausible member be tried.
  // The plain log-normal prior (no fault tail): the engineer's 0.1 % is taken at its word here;
  // with the default tail MB is the answer, flagged (next test).
  const auto [nominal, tests] = MountMBStifferThanItsRating();
  DiagnoseOptions options;
  options.max_effects = 1;
  options.max_fitted_singles = 1;
  options.stiffness_fault_share = 0.0;
  const Diagnosis d = Diagnose(nominal, tests, options);
  int fitted_mounts = 0;
  for (const Candidate& c : d.candidates) {
    if (c.effects.size() != 1 || c.effects[0].kind != EffectKind::kStiffnessScale || c.target.rfind("mounts/", 0) != 0)
      continue;
    ++fitted_mounts;
    EXPECT_NE(c.target, "mounts/MB") << d.explanation;
  }
  EXPECT_EQ(fitted_mounts, 1) << d.explanation;
}

TEST(Diagnose, AStiffnessFarOutsideItsStatedUncertaintyIsFoundAndFlagged) {
  // The same mount MB, 1.3× stiffer than a rating the engineer gives to 0.1 % (262 σ of it).
  // Priors, not cliffs: a stiffness is as stated within its uncertainty or grossly off (the fault
  // tail, 2 % of the prior, σ = 3 in ln factor), so the only reading that fits is rank 1 with its
  // value, and flagged in words. With the plain log-normal (share 0) its prior cost, 3.4e4, buries
  // it under readings that leave the error unexplained.
  const auto [nominal, tests] = MountMBStifferThanItsRating();
  DiagnoseOptions options;
  options.max_effects = 1;
  for (double share : {0.02, 0.0}) {
    options.stiffness_fault_share = share;
    const Diagnosis d = Diagnose(nominal, tests, options);
    ASSERT_FALSE(d.candidates.empty());
    const Candidate& first = d.candidates.front();
    if (share > 0.0) {
      ASSERT_EQ(first.target, "mounts/MB") << d.explanation;
      EXPECT_EQ(first.kind, "stiffness_scale") << d.explanation;
      ASSERT_EQ(first.parameters.size(), 1u);
      // 0.1 % frequency noise on two setups: the factor to 1 %.
      EXPECT_NEAR(first.parameters.front().value, 1.3, 0.013) << d.explanation;
      EXPECT_TRUE(first.parameters.front().outside_prior) << d.explanation;
      EXPECT_GT(first.probability, 0.9) << d.explanation;
      ASSERT_FALSE(first.flags.empty()) << d.explanation;
      EXPECT_NE(first.flags.front().find("check it"), std::string::npos) << first.flags.front();
    } else {
      EXPECT_NE(first.target, "mounts/MB") << "without the tail the prior buries the truth: " << d.explanation;
    }
  }
}

TEST(Diagnose, TheModelFilesFaultTailOverridesTheDefault) {
  // The same mount MB as above, with the default options: a model whose [priors] says
  // stiffness_fault_share = 0 (the engineer rules gross faults out) buries MB as the plain
  // log-normal does; one that leaves the key out keeps the default tail and finds MB.
  auto [nominal, tests] = MountMBStifferThanItsRating();
  DiagnoseOptions options;
  options.max_effects = 1;
  nominal.stiffness_fault_share = 0.0;
  const Diagnosis ruled_out = Diagnose(nominal, tests, options);
  ASSERT_FALSE(ruled_out.candidates.empty());
  EXPECT_NE(ruled_out.candidates.front().target, "mounts/MB") << ruled_out.explanation;
  nominal.stiffness_fault_share.reset();
  nominal.stiffness_fault_width = 3.0;
  const Diagnosis tail = Diagnose(nominal, tests, options);
  ASSERT_FALSE(tail.candidates.empty());
  EXPECT_EQ(tail.candidates.front().target, "mounts/MB") << tail.explanation;
}

TEST(EffectProbabilities, SumOverTheCandidatesThatHoldEachEffect) {
  // Four ranked candidates with probabilities 0.4 / 0.3 / 0.2 / 0.1. By hand:
  //   series_compliance on bearings: 0.4 + 0.3 + 0.2 = 0.9
  //   added_mass on points:* (single points): 0.4 + 0.3 = 0.7 (points:1,2 is not a single point)
  //   stiffness_scale on joints/*: 0.2 + 0.1 = 0.3, with joints/J1 0.2 and joints/J2 0.1 —
  //   counted once per candidate even where one candidate holds two members (J1 and J2 in #3).
  auto effect = [](EffectKind kind, const EffectTarget& target) {
    Effect e;
    e.kind = kind;
    e.target = target;
    return e;
  };
  std::vector<Candidate> ranked(4);
  ranked[0].effects = {effect(EffectKind::kSeriesCompliance, EffectTarget::Named("bearings")),
                       effect(EffectKind::kAddedMass, EffectTarget::Points({101}))};
  ranked[1].effects = {effect(EffectKind::kSeriesCompliance, EffectTarget::Named("bearings")),
                       effect(EffectKind::kAddedMass, EffectTarget::Points({102}))};
  ranked[2].effects = {effect(EffectKind::kSeriesCompliance, EffectTarget::Named("bearings")),
                       effect(EffectKind::kStiffnessScale, EffectTarget::MemberOf("joints", "J1")),
                       effect(EffectKind::kStiffnessScale, EffectTarget::MemberOf("joints", "J2"))};
  ranked[3].effects = {effect(EffectKind::kStiffnessScale, EffectTarget::MemberOf("joints", "J2")),
                       effect(EffectKind::kAddedMass, EffectTarget::Points({1, 2}))};
  const double p[] = {0.4, 0.3, 0.2, 0.1};
  for (int i = 0; i < 4; ++i) ranked[i].probability = p[i];
  const std::vector<EffectProbability> out = EffectProbabilities(ranked);
  auto find = [&](EffectKind kind, const EffectTarget& target) {
    for (const auto& e : out)
      if (e.kind == kind && e.target == target) return e.probability;
    return -1.0;
  };
  EXPECT_NEAR(find(EffectKind::kSeriesCompliance, EffectTarget::Named("bearings")), 0.9, 1e-12);
  EXPECT_NEAR(find(EffectKind::kAddedMass, EffectTarget::EveryPoint()), 0.7, 1e-12);
  EXPECT_NEAR(find(EffectKind::kAddedMass, EffectTarget::Points({101})), 0.4, 1e-12);
  EXPECT_NEAR(find(EffectKind::kAddedMass, EffectTarget::Points({1, 2})), 0.1, 1e-12);
  EXPECT_NEAR(find(EffectKind::kStiffnessScale, EffectTarget::EveryMemberOf("joints")), 0.3, 1e-12);
  EXPECT_NEAR(find(EffectKind::kStiffnessScale, EffectTarget::MemberOf("joints", "J1")), 0.2, 1e-12);
  EXPECT_NEAR(find(EffectKind::kStiffnessScale, EffectTarget::MemberOf("joints", "J2")), 0.3, 1e-12);
  ASSERT_FALSE(out.empty());
  for (size_t i = 1; i < out.size(); ++i) EXPECT_GE(out[i - 1].probability, out[i].probability) << "most probable first";
}

TEST(EffectProbabilities, EqualProbabilitiesKeepTheOrderOfTheKindsNames) {
  // One candidate holds every effect, so all sum alike: DIAG.json lists them by kind name, then
  // target (as when kinds were text), not in the vocabulary's order.
  Candidate c;
  c.probability = 1.0;
  c.effects = {Effect{EffectKind::kSeriesCompliance, EffectTarget::Named("bearings"), {}, std::nullopt, 0},
               Effect{EffectKind::kAddedMass, EffectTarget::Points({101}), {{"mass", 0.01}}, std::nullopt, 0},
               Effect{EffectKind::kGroundSpring, EffectTarget::Named("base"), {{"k", 1e5}}, std::nullopt, 0}};
  const std::vector<EffectProbability> out = EffectProbabilities({c});
  std::vector<std::string> order;
  for (const EffectProbability& e : out) order.push_back(model::KindName(e.kind) + " " + model::TargetText(e.target));
  EXPECT_EQ(order, (std::vector<std::string>{"added_mass points:*", "added_mass points:101", "ground_spring base",
                                             "series_compliance bearings"}));
}

}  // namespace
}  // namespace ema::diagnose
