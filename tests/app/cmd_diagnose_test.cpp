// The first screen of `ema diagnose` (app/cmd_diagnose.cpp) for a model whose form is wrong in a
// way no effect of the vocabulary expresses (docs/diagnose.md "Model error"): it says the model is
// not adequate first, and when no effect beats the model as given it says that what is missing
// lies outside the vocabulary — never "no missing effect found" above "not adequate".
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <filesystem>
#include <random>
#include <sstream>

#include "ema/diagnose/diagnose.hpp"
#include "ema/formats/model_file.hpp"
#include "ema/model/solve.hpp"
#include "stages.hpp"

namespace ema::app {
namespace {
namespace fs = std::filesystem;

// The two-body stack of the diagnosis benchmark with every body 1.2 % heavier than its model and
// every spring off by 1 % of its own (seed 11): each mode about 0.6 % low, the test's σ 0.1 %.
std::vector<diagnose::SetupModes> SpreadMassTest(const model::Model& nominal) {
  model::Model truth = nominal;
  std::mt19937 rng(11);
  std::normal_distribution<double> g;
  for (auto& s : truth.springs) s.stiffness_factor *= std::exp(0.01 * g(rng));
  for (auto& b : truth.bodies) {
    b.mass *= 1.012;
    b.inertia *= 1.012;
    b.products *= 1.012;
  }
  ModeSet modes = model::Solve(truth, {}).modes;
  for (Mode& mode : modes.modes) {
    mode.frequency_hz *= 1.0 + 1e-3 * g(rng);
    mode.pole = FrequencyAndDampingToPole(mode.frequency_hz, mode.damping_ratio);
  }
  modes.source = "spread mass";
  return {{"", modes}};
}

TEST(DiagnoseWords, AModelWrongOutsideTheVocabularySaysSoFirst) {
  const model::Model nominal =
      formats::ReadModelFile(fs::path(EMA_SOURCE_DIR) / "tests/diagnose/data/benchmark-stack2.toml");
  DiagnoseConfig config;
  config.options.max_effects = 2;
  std::ostringstream out;
  const DiagnoseStageResult stage = RunDiagnoseStage(config, nominal, SpreadMassTest(nominal), out);
  const diagnose::Candidate& first = stage.diagnosis.candidates.front();
  ASSERT_FALSE(first.noise_consistent) << stage.summary;
  ASSERT_TRUE(first.model_error.dominates) << stage.summary;
  // The inadequacy first, with the error the modes share (the spread mass: ~0.6 % on all).
  EXPECT_EQ(stage.summary.rfind("The model is NOT adequate to this test", 0), 0u) << stage.summary;
  EXPECT_NE(stage.summary.find("shared by all of them"), std::string::npos) << stage.summary;
  EXPECT_NE(stage.summary.find("distributed stiffness too high or mass too low"), std::string::npos) << stage.summary;
  // Rank 1 is the model as given (no point mass invented), said as what it is.
  ASSERT_TRUE(first.effects.empty()) << stage.summary;
  EXPECT_EQ(stage.summary.find("no missing effect found"), std::string::npos) << stage.summary;
  EXPECT_NE(stage.summary.find("what is missing is outside the vocabulary"), std::string::npos) << stage.summary;
  EXPECT_TRUE(stage.json.at("findings").empty());
}

}  // namespace
}  // namespace ema::app
