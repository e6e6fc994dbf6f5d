// The first screen of `ema diagnose` (app/cmd_diagnose.cpp) for a model whose form is wrong in a
// way no effect of the vocabulary expresses (docs/diagnose.md "Model error"): it says the model is
// not adequate first, and when no effect beats the model as given it says that what is missing
// lies outside the vocabulary — never "no missing effect found" above "not adequate".
#include <gtest/gtest.h>

#include <sstream>

#include "ema/diagnose/diagnose.hpp"
#include "stack_truths.hpp"
#include "stages.hpp"

namespace ema::app {
namespace {

TEST(DiagnoseWords, AModelWrongOutsideTheVocabularySaysSoFirst) {
  // The two-body stack of the diagnosis benchmark with every body 1.2 % heavier than its model
  // and every spring off by 1 % of its own (seed 11): each mode about 0.6 % low, the test's σ
  // 0.1 % (the truth of ModelError.AMassSpreadOverTheBodiesIsTheModelsErrorNotAnAddedMass).
  const model::Model nominal = test::Stack();
  model::Model truth = test::Scattered(nominal, 0.01, 11);
  test::SpreadMass(&truth, 1.012);
  DiagnoseConfig config;
  config.options.max_effects = 2;
  std::ostringstream out;
  const DiagnoseStageResult stage = RunDiagnoseStage(config, nominal, {{"", test::Measured(truth, 11)}}, out);
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
