// `ema diagnose` options end to end (issue 17): --criterion bic|aicc, --shape-weight and
// --force-level each change the output as documented, so an ignored or mis-wired option fails.
// Test modes: the guideway sample's own fitted modes (`ema run`, shared: tests/guideway_run.hpp).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "diagnose/chain_helpers.hpp"
#include "guideway_run.hpp"
#include "ema/formats/io.hpp"

namespace ema {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using test_chain::RunEma;
using test_chain::Slurp;

const fs::path kSample = fs::path(EMA_SOURCE_DIR) / "samples" / "guideway";

class DiagnoseCli : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new fs::path(fs::path(EMA_TEST_TMP_DIR) / ("diagnose-cli-" + std::to_string(getpid())));
    fs::remove_all(*dir_);
    fs::create_directories(*dir_);
    // The sample's run shared with every test process (tests/guideway_run.hpp): its modes.
    const test::SharedGuidewayRun run = test::GuidewayRunOnce();
    run_ok_ = run.exit_code == 0;
    run_ = new fs::path(run.out);
    run_log_ = new fs::path(run.log);
  }
  static void TearDownTestSuite() {
    std::error_code ignored;
    fs::remove_all(*dir_, ignored);
    delete dir_;
    delete run_;
    delete run_log_;
  }
  void SetUp() override { ASSERT_TRUE(run_ok_) << Slurp(*run_log_); }
  /// `ema diagnose` of the sample's model against both setups, with `extra` options.
  json Diagnose(const std::string& tag, const std::string& extra) {
    const fs::path out = *dir_ / (tag + ".json");
    const std::string args = "diagnose \"" + (kSample / "model.toml").string() + "\" --test stud-5um=\"" +
                             (*run_ / "stud-5um/modes.unv").string() + "\" --test stud-9um=\"" +
                             (*run_ / "stud-9um/modes.unv").string() + "\" --json \"" + out.string() + "\" " + extra;
    EXPECT_EQ(RunEma(*dir_, args, tag + ".log"), 0) << Slurp(*dir_ / (tag + ".log"));
    return json::parse(Slurp(out));
  }
  static fs::path* dir_;
  static fs::path* run_;
  static fs::path* run_log_;
  static bool run_ok_;
};
fs::path* DiagnoseCli::dir_ = nullptr;
fs::path* DiagnoseCli::run_ = nullptr;
fs::path* DiagnoseCli::run_log_ = nullptr;
bool DiagnoseCli::run_ok_ = false;

TEST_F(DiagnoseCli, CriterionBicAndAiccScoreByTheirFormulas) {
  // With n residuals, cost J and k fitted parameters: BIC = J + k ln n, AICc = J + 2k + 2k(k+1)/(n−k−1).
  for (const std::string criterion : {"bic", "aicc"}) {
    const json d = Diagnose(criterion, "--criterion " + criterion + " --max-effects 2");
    EXPECT_EQ(d.at("criterion"), criterion);
    const double n = d.at("residual_count").get<double>();
    ASSERT_GT(d.at("candidates").size(), 3u);
    int checked = 0;
    for (const auto& c : d.at("candidates")) {
      if (c.contains("error") || !c.at("score").is_number() || !c.at("cost").is_number()) continue;
      const double k = static_cast<double>(c.at("parameters").size());
      const double cost = c.at("cost").get<double>();
      const double expected = criterion == "bic" ? cost + k * std::log(n) : cost + 2 * k + 2 * k * (k + 1) / (n - k - 1);
      EXPECT_NEAR(c.at("score").get<double>(), expected, 1e-9 * std::max(1.0, std::abs(expected))) << c.at("kind");
      ++checked;
    }
    EXPECT_GT(checked, 3);
  }
}

TEST_F(DiagnoseCli, ProbabilitiesAreTheNormalisedEvidence) {
  // probability_i = exp(−score_i/2) / Σ exp(−score_j/2) with score = −2 log evidence: on the
  // guideway several candidates (the sensors' mass at one point or another) share the
  // probability, so the ratios p_i/p_1 = exp(−(s_i − s_1)/2) are checked where both are > 1e-9.
  const json d = Diagnose("evidence", "");
  const auto& c = d.at("candidates");
  ASSERT_GT(c.size(), 2u);
  double sum = 0.0;
  for (const auto& k : c) sum += k.at("probability").get<double>();
  EXPECT_NEAR(sum, 1.0, 1e-9);
  const double p1 = c[0].at("probability").get<double>(), s1 = c[0].at("score").get<double>();
  EXPECT_NEAR(c[0].at("log_evidence").get<double>(), -0.5 * s1, 1e-9 * std::abs(s1));
  int checked = 0;
  for (size_t i = 1; i < c.size(); ++i) {
    const double p = c[i].at("probability").get<double>();
    if (!(p > 1e-9) || !c[i].at("score").is_number()) continue;
    EXPECT_NEAR(std::log(p / p1), -0.5 * (c[i].at("score").get<double>() - s1), 1e-6) << c[i].at("description");
    ++checked;
  }
  EXPECT_GE(checked, 2) << "the guideway's near-equal candidates";
}

double NoneCost(const json& d) {
  for (const auto& c : d.at("candidates"))
    if (c.at("kind") == "none") return c.at("cost").get<double>();
  return -1.0;
}

TEST_F(DiagnoseCli, ShapeWeightSetsTheShapeSigma) {
  // --shape-weight W means a shape σ of 0.001 / W (documented old form of --shape-sigma): with
  // W = 1 the MAC residuals weigh 10× more than with the default σ 0.01, so the model as given
  // (whose MACs are below 1) costs more.
  // Both with --shape-residual mac, the residual the shape σ belongs to.
  const json base = Diagnose("shape-default", "--max-effects 1 --shape-residual mac");
  const json heavy = Diagnose("shape-heavy", "--max-effects 1 --shape-residual mac --shape-weight 1");
  EXPECT_DOUBLE_EQ(base.at("options").at("shape_sigma").get<double>(), 0.01);
  EXPECT_DOUBLE_EQ(heavy.at("options").at("shape_sigma").get<double>(), 0.001);
  EXPECT_EQ(base.at("options").at("shape_residual"), "mac");
  EXPECT_GT(NoneCost(heavy), NoneCost(base));
}

TEST_F(DiagnoseCli, ShapeDofSigmaSetsTheFloorOfTheShapeResiduals) {
  // --shape-dof-sigma S (per-DOF shape residuals, the default): a floor half the default's about doubles
  // each shape residual of the model as given (whose shapes differ from the test's by more than
  // the fit's σ), so its cost grows; the options say what was used. An unknown residual is refused.
  const json base = Diagnose("dof-default", "--max-effects 1");
  const json tight = Diagnose("dof-tight", "--max-effects 1 --shape-dof-sigma 0.05");
  EXPECT_EQ(base.at("options").at("shape_residual"), "per-dof");
  EXPECT_DOUBLE_EQ(base.at("options").at("shape_dof_sigma").get<double>(), 0.1);
  EXPECT_DOUBLE_EQ(tight.at("options").at("shape_dof_sigma").get<double>(), 0.05);
  EXPECT_GT(NoneCost(tight), NoneCost(base));
  const std::string bad = "diagnose \"" + (kSample / "model.toml").string() + "\" --test stud-5um=\"" +
                          (*run_ / "stud-5um/modes.unv").string() + "\" --shape-residual per_dof";
  EXPECT_EQ(RunEma(*dir_, bad, "dof-bad.log"), 2);
  EXPECT_NE(Slurp(*dir_ / "dof-bad.log").find("--shape-residual must be per-dof or mac"), std::string::npos);
}

TEST_F(DiagnoseCli, ExactFormLeavesTheModelErrorOut) {
  // --exact-form: the likelihood without model error (docs/diagnose.md "Model error"). The model
  // as given misses the mount compliance by far more than the test's σ, so by default its
  // inferred model error dominates; with --exact-form no scale is inferred (0) and the options
  // say so. Rank 1 is the same reading either way (the guideway's form is exact).
  const json base = Diagnose("model-error", "--max-effects 1");
  const json exact = Diagnose("exact-form", "--max-effects 1 --exact-form");
  EXPECT_TRUE(base.at("options").at("model_error").get<bool>());
  EXPECT_FALSE(exact.at("options").at("model_error").get<bool>());
  auto none = [](const json& d) -> const json& {
    for (const auto& c : d.at("candidates"))
      if (c.at("kind") == "none") return c;
    return d.at("candidates").at(0);
  };
  EXPECT_GT(none(base).at("model_error").at("frequency_rel").get<double>(), 0.01);
  EXPECT_TRUE(none(base).at("model_error").at("dominates").get<bool>());
  EXPECT_EQ(none(exact).at("model_error").at("frequency_rel").get<double>(), 0.0);
  EXPECT_EQ(base.at("candidates").at(0).at("target"), exact.at("candidates").at(0).at("target"));
  EXPECT_EQ(base.at("model_error"), base.at("candidates").at(0).at("model_error"));
  // The first screen's effects as data (DIAG.json findings, docs/diagnose.md): one per effect of
  // rank 1, its description, its fitted values with σ and per setup its springs' stiffness.
  const json& first = base.at("candidates").at(0);
  ASSERT_EQ(base.at("findings").size(), first.at("effects").size());
  const json& finding = base.at("findings").at(0);
  EXPECT_EQ(finding.at("kind"), first.at("effects").at(0).at("kind"));
  EXPECT_EQ(finding.at("target"), "bearings");
  EXPECT_NE(finding.at("description").get<std::string>().find("in series with group 'bearings'"), std::string::npos)
      << finding.at("description");
  ASSERT_EQ(finding.at("parameters").size(), first.at("parameters").size());
  const json& parameter = finding.at("parameters").at(0);
  EXPECT_EQ(parameter.at("value"), first.at("parameters").at(parameter.at("name").get<std::string>()));
  EXPECT_GT(parameter.at("sigma").get<double>(), 0.0);
  // Each test's setup, the springs with the compliance softer than the air film alone.
  ASSERT_FALSE(finding.at("springs").empty());
  for (const json& s : finding.at("springs")) {
    EXPECT_GT(s.at("per_spring_n_per_m").get<double>(), 0.0);
    EXPECT_LT(s.at("per_spring_n_per_m").get<double>(), s.at("element_n_per_m").get<double>());
  }
  EXPECT_GT(finding.at("probability").get<double>(), 0.9);
}

TEST_F(DiagnoseCli, EffectPriorOddsIsAnOptionThatValidatesItself) {
  // --effect-prior-odds (DiagnoseOptions::effect_prior_odds, docs/diagnose.md "Model error"): the
  // default 0.25 and a given value reach DIAG.json's options; each effect's evidence moves by
  // ln(odds ratio) per effect, so rank 1's probability (one effect) moves and its reading does not
  // (the mount compliance fits the guideway far beyond any prior); outside (0, 1] is bad usage.
  const json base = Diagnose("odds-default", "--max-effects 1");
  const json even = Diagnose("odds-even", "--max-effects 1 --effect-prior-odds 1");
  EXPECT_DOUBLE_EQ(base.at("options").at("effect_prior_odds").get<double>(), 0.25);
  EXPECT_DOUBLE_EQ(even.at("options").at("effect_prior_odds").get<double>(), 1.0);
  EXPECT_EQ(base.at("candidates").at(0).at("target"), even.at("candidates").at(0).at("target"));
  auto log_evidence = [](const json& d, const std::string& kind) {
    for (const auto& c : d.at("candidates"))
      if (c.at("kind") == kind) return c.at("log_evidence").get<double>();
    return std::nan("");
  };
  // "none" holds no effect: its evidence is the same; a one-effect reading gains ln 4.
  EXPECT_NEAR(log_evidence(even, "none"), log_evidence(base, "none"), 1e-9);
  const std::string kind = base.at("candidates").at(0).at("kind");
  EXPECT_NEAR(log_evidence(even, kind) - log_evidence(base, kind), std::log(4.0), 1e-6);
  for (const char* bad : {"0", "1.5", "-1"})
    EXPECT_EQ(RunEma(*dir_, "diagnose \"" + (kSample / "model.toml").string() + "\" --test \"" +
                                (*run_ / "stud-5um/modes.unv").string() + "\" --effect-prior-odds " + bad,
                     std::string("odds-") + bad + ".log"),
              2)
        << bad;
}

TEST_F(DiagnoseCli, ForceLevelReportsTheAmplitudeTrend) {
  // Three levels built from the stud-5um modes with every frequency lowered by 0 %, 0.5 % and
  // 1 % (and damping unchanged): each mode is "softening" with a change of −1 % from the lowest
  // to the highest level, and damping "none" (ema amplitude's analysis, docs/amplitude.md).
  const ModeSet modes = formats::ReadModeSet(*run_ / "stud-5um/modes.unv");
  const double shift[] = {1.0, 0.995, 0.99};
  std::string levels;
  for (int l = 0; l < 3; ++l) {
    ModeSet m = modes;
    for (Mode& mode : m.modes) {
      mode.frequency_hz *= shift[l];
      mode.pole *= shift[l];
    }
    const fs::path p = *dir_ / ("level" + std::to_string(l) + ".unv");
    formats::WriteModeSet(p, m);
    levels += " --force-level " + std::to_string(10 * (l + 1)) + "=\"" + p.string() + "\"";
  }
  const json d = Diagnose("force-levels", "--max-effects 1" + levels);
  ASSERT_TRUE(d.contains("nonlinearity"));
  const json& nl = d.at("nonlinearity");
  EXPECT_TRUE(nl.at("flagged").get<bool>());
  EXPECT_EQ(nl.at("level_kind"), "peak_force");
  ASSERT_EQ(nl.at("modes").size(), modes.modes.size());
  for (const auto& m : nl.at("modes")) {
    EXPECT_EQ(m.at("frequency_trend"), "softening");
    EXPECT_NEAR(m.at("frequency_change_pct").get<double>(), -1.0, 1e-3);
    EXPECT_EQ(m.at("damping_trend"), "none");
    EXPECT_EQ(m.at("levels").size(), 3u);
  }
  // One level alone is bad usage.
  EXPECT_EQ(RunEma(*dir_, "diagnose \"" + (kSample / "model.toml").string() + "\" --test \"" +
                            (*run_ / "stud-5um/modes.unv").string() + "\" --force-level 10=\"" +
                            (*dir_ / "level0.unv").string() + "\"",
                   "one-level.log"),
            2);
}

}  // namespace
}  // namespace ema
