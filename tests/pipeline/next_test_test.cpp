// pipeline::PlanNextTest: a test whose sensors sit symmetrically on a symmetric bridge cannot tell
// a mass at a point from one at its mirror point (the diagnosis's look-alikes); the next test
// keeps that test's set and hammer and adds one set where the two readings' shapes differ.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>

#include "ema/formats/model_file.hpp"
#include "ema/pipeline/run.hpp"
#include "model/fe_frame.hpp"

namespace ema::pipeline {
namespace {

namespace fs = std::filesystem;

diagnose::Candidate Mass(int rank, int point, double probability) {
  diagnose::Candidate c;
  c.rank = rank;
  c.kind = "added_mass";
  c.target = "points:" + std::to_string(point);
  c.probability = probability;
  c.effects = {
      {model::EffectKind::kAddedMass, model::EffectTarget::Points({point}), {{"mass", 60.0}}, std::nullopt, 0}};
  return c;
}

TEST(NextTest, OneMoreSetSeparatesMirrorReadingsASymmetricTestCannot) {
  testing::FrameSpec spec;
  spec.segments = 20, spec.zones = 4, spec.cross_every = 2, spec.points_per_girder = 19;
  const fs::path dir = fs::path(EMA_TEST_TMP_DIR) / "next-test-frame";
  const testing::FrameFiles files = testing::WriteFrame(dir, spec);
  const model::Model m = formats::ReadModelFile(files.model);
  formats::Project project;
  project.tests.push_back({});
  project.tests[0].name = "bridge";
  // The test: six +Z sensors in one set, mirror-symmetric about mid-span; the hammer off mid-span
  // (at mid-span it would excite no mode antisymmetric about it, and no set could help).
  std::vector<TestResult> tests(1);
  tests[0].fit.emplace();
  FrfSet frfs;
  for (int node : {1003, 1017, 1010, 2003, 2017, 2010}) frfs.outputs.push_back({node, 3});
  frfs.output_sets.assign(frfs.outputs.size(), 0);
  frfs.references = {{1003, 3}};
  tests[0].frfs = frfs;
  // Rank 1 a mass at 1005, its mirror 1015 within a factor 20, a far reading beyond it.
  diagnose::Diagnosis d;
  d.candidates = {Mass(1, 1005, 0.40), Mass(2, 1015, 0.38), Mass(3, 2010, 0.01)};
  const std::optional<NextTest> next = PlanNextTest(m, project, tests, d);
  ASSERT_TRUE(next);
  EXPECT_EQ(next->readings, (std::vector<std::string>{"added_mass on points:1005", "added_mass on points:1015"}));
  ASSERT_EQ(next->kept_sets, 1);
  ASSERT_EQ(next->plan.sets.size(), 2u);
  EXPECT_EQ(next->plan.sets[0], frfs.outputs);  // the test's own set, kept as it was
  EXPECT_EQ(next->plan.sets[1].size(), 6u);    // one more of the same size
  for (const Dof& dof : next->plan.sets[1])
    EXPECT_EQ(std::count(frfs.outputs.begin(), frfs.outputs.end(), dof), 0) << DofName(dof);
  EXPECT_EQ(next->plan.references, frfs.references);
  ASSERT_EQ(next->plan.separations.size(), 1u);
  const planning::Separation& s = next->plan.separations[0];
  // Symmetric sensors see mirror shapes nearly alike: 2.2σ apart with the shapes per DOF (0.78σ
  // when the diagnosis weighed 1 − MAC, before 2026-11-27) — below the 3σ that would settle it;
  // the new set more than doubles it.
  EXPECT_LT(s.sigma_before, 3.0) << s.sigma_before;
  EXPECT_GT(s.sigma_after, 2.0 * s.sigma_before);
  std::string added;
  for (const Dof& dof : next->plan.sets[1]) added += DofName(dof) + " ";
  EXPECT_GT(s.sigma_after, 1.5) << s.sigma_before << " -> " << s.sigma_after << " with " << added;
  // No look-alike: nothing to plan.
  d.candidates[1].probability = 0.01;
  EXPECT_FALSE(PlanNextTest(m, project, tests, d));
  fs::remove_all(dir);
}

}  // namespace
}  // namespace ema::pipeline
