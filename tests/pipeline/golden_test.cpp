// The typed pipeline gives the numbers `ema run` gave before it was one (issue 38): the guideway
// sample run through pipeline::Run, its DIAG.json (pipeline::DiagnosisJson) and each test's
// MODES.json (pipeline::FitModesJson) against tests/data/golden/guideway-run.json, written by the
// run of 2026-11-27 before the change.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "ema/formats/project_file.hpp"
#include "ema/pipeline/json.hpp"
#include "ema/pipeline/run.hpp"
#include "golden.hpp"

namespace ema::pipeline {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

TEST(Golden, GuidewayRunGivesTheNumbersOfTheRunBeforeThePipeline) {
  const fs::path sample = fs::path(EMA_SOURCE_DIR) / "samples" / "guideway" / "project.toml";
  const RunResult run = pipeline::Run(PlanFromProject(formats::ReadProjectFile(sample), fs::path(EMA_TEST_TMP_DIR) / "golden-guideway"));
  ASSERT_TRUE(run.Succeeded());
  ASSERT_TRUE(run.diagnosis);
  std::ifstream in(fs::path(EMA_SOURCE_DIR) / "tests" / "data" / "golden" / "guideway-run.json");
  const json golden = json::parse(in);
  int compared = 0;
  test::ExpectSameNumbers(golden["diagnosis"], DiagnosisJson(*run.diagnosis), "diagnosis", &compared);
  for (std::size_t t = 0; t < run.tests.size(); ++t) {
    const std::string& name = run.plan.project.tests[t].name;
    ASSERT_TRUE(run.tests[t].fit) << name;
    test::ExpectSameNumbers(golden["modes"][name], FitModesJson(*run.tests[t].fit, *run.tests[t].frfs), "modes/" + name, &compared);
  }
  EXPECT_GT(compared, 500);  // the whole ranking, every mode row and every test mode were compared
}

}  // namespace
}  // namespace ema::pipeline
