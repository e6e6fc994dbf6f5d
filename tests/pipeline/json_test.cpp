// pipeline/json.hpp: the findings and DIAG.json as a whole dump to valid JSON whatever bytes the
// model's texts hold (fuzz_json_results found FindingsJson passing a target's Latin-1 byte to
// nlohmann, whose dump() then threw type_error 316 after the whole diagnosis), and the numbers
// are written as they are.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "ema/pipeline/json.hpp"

namespace ema::pipeline {
namespace {

Findings LatinOneFindings() {
  Findings f;
  EffectFinding e;
  e.effect.kind = model::EffectKind::kAddedMass;
  e.effect.target = model::EffectTarget::Named("point:\xB2");  // Latin-1 '²': not UTF-8
  e.effect.parameters["m"] = 0.015;
  diagnose::FittedParameter p;
  p.effect_kind = e.effect.kind;
  p.target = e.effect.target;
  p.name = "m";
  p.value = 0.015;
  p.sigma = 0.002;
  e.parameters = {p};
  e.probability = 0.75;
  e.springs = {{"setup \xE9", 2.5e6, kNaN}};
  f.effects = {e};
  return f;
}

TEST(PipelineJson, FindingsWithLatinOneTextsDumpAsUtf8) {
  const nlohmann::json j = FindingsJson(LatinOneFindings());
  std::string text;
  ASSERT_NO_THROW(text = j.dump());
  const nlohmann::json back = nlohmann::json::parse(text);
  ASSERT_EQ(back.size(), 1u);
  EXPECT_EQ(back[0]["target"], "point:\u00B2");  // the byte read as Latin-1
  EXPECT_EQ(back[0]["springs"][0]["setup"], "setup \u00E9");
  EXPECT_EQ(back[0]["springs"][0]["per_spring_n_per_m"], 2.5e6);
  EXPECT_TRUE(back[0]["springs"][0]["element_n_per_m"].is_null());  // NaN: not applicable
  EXPECT_EQ(back[0]["parameters"][0]["value"], 0.015);
  EXPECT_EQ(back[0]["parameters"][0]["sigma"], 0.002);
  EXPECT_EQ(back[0]["probability"], 0.75);
}

TEST(PipelineJson, DiagnosisWithLatinOneFindingsAndAmplitudeSummaryDumps) {
  DiagnoseStage stage;
  stage.findings = LatinOneFindings();
  correlation::AmplitudeResult nonlinearity;
  nonlinearity.summary = "level \xB5N";  // Latin-1 'µ'
  stage.nonlinearity = nonlinearity;
  const nlohmann::json j = DiagnosisJson(stage);
  std::string text;
  ASSERT_NO_THROW(text = j.dump());
  const nlohmann::json back = nlohmann::json::parse(text);
  EXPECT_EQ(back["findings"][0]["target"], "point:\u00B2");
  EXPECT_EQ(back["nonlinearity"]["summary"], "level \u00B5N");
  EXPECT_EQ(back["nonlinearity"]["flagged"], false);
}

}  // namespace
}  // namespace ema::pipeline
