// The diagnosis on FE models built from parts (issue 27): a footbridge-like frame of 972 DOFs,
// 17 stiffness parts and a singular (lumped) mass matrix, whose test modes come as MODES.json —
// 58 measured DOFs, frequencies with their σ. Known truths: one member part softened, one group
// softened, a part plus an added mass, and a model missing what no part can express.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <fstream>
#include <limits>
#include <random>

#include "ema/diagnose/diagnose.hpp"
#include "ema/formats/json_codecs.hpp"
#include "ema/formats/io.hpp"
#include "ema/formats/model_file.hpp"
#include "ema/model/effects.hpp"
#include "ema/model/solve.hpp"
#include "model/fe_frame.hpp"

using ema::model::EffectTarget;

namespace ema::diagnose {
namespace {

namespace fs = std::filesystem;
using model::EffectKind;

// One folder per process: ctest -j runs these tests as separate processes at once, and a shared
// folder let one process rewrite the frame's files while another read them (a flake of
// PartsDiagnosis.APartPlusAnAddedMass under ctest -j2).
const fs::path kDir = fs::path(EMA_TEST_TMP_DIR) / "diagnose" / ("frame-" + std::to_string(::getpid()));

// The frame, written once per test program and removed when it ends.
const ema::testing::FrameFiles& Frame() {
  struct Written {
    ema::testing::FrameFiles files = ema::testing::WriteFrame(kDir);
    ~Written() {
      std::error_code ec;
      fs::remove_all(kDir, ec);
    }
  };
  static const Written written;
  return written.files;
}

// Test modes of `truth`: the lowest `count` vertical modes (most of their motion at the test points
// in Z) measured in +Z only, as a footbridge is; frequencies perturbed by relative noise `noise`
// (seeded) and given σ = max(noise, 1e-4)·f.
ModeSet Measure(const model::Model& truth, int count, double noise, unsigned seed) {
  model::SolveOptions so;
  so.max_modes = 3 * count;
  const model::Solution s = model::Solve(truth, so);
  ModeSet out;
  std::vector<Eigen::Index> rows;
  for (size_t d = 0; d < s.modes.dofs.size(); ++d)
    if (s.modes.dofs[d].direction == 3) {
      rows.push_back(static_cast<Eigen::Index>(d));
      out.dofs.push_back(s.modes.dofs[d]);
    }
  std::mt19937 rng(seed);
  std::normal_distribution<double> gauss(0.0, 1.0);
  for (const Mode& m : s.modes.modes) {
    if (static_cast<int>(out.modes.size()) == count) break;
    double z = 0.0;
    for (Eigen::Index r : rows) z += std::norm(m.shape(r));
    if (z < 0.5 * m.shape.squaredNorm()) continue;  // a lateral or axial mode: not seen in Z
    Mode t = m;
    t.shape.resize(static_cast<Eigen::Index>(rows.size()));
    for (size_t k = 0; k < rows.size(); ++k) t.shape(static_cast<Eigen::Index>(k)) = m.shape(rows[k]);
    t.frequency_hz = m.frequency_hz * (1.0 + noise * gauss(rng));
    t.frequency_std_hz = std::max(noise, 1e-4) * m.frequency_hz;
    out.modes.push_back(t);
  }
  return out;
}

model::Model WithEffects(std::vector<model::Effect> effects) {
  model::Model m = formats::ReadModelFile(Frame().model);
  for (const auto& e : effects) m = model::ApplyEffect(m, e);
  return m;
}

TEST(PartsDiagnosis, OneMemberPartSoftenedRanksFirstWithItsFactor) {
  const model::Model nominal = formats::ReadModelFile(Frame().model);
  ASSERT_GE(Frame().dofs, 900);
  ASSERT_GE(Frame().parts, 15);
  const ModeSet test = Measure(
      WithEffects({{EffectKind::kStiffnessScale, EffectTarget::MemberOf("girders", "G3"), {{"factor", 0.3}}, {}, 0}}),
      6, 1e-3, 1);
  const Diagnosis d = Diagnose(nominal, {{"", test}});
  const Candidate& first = d.candidates.front();
  ASSERT_EQ(first.effects.size(), 1u) << d.explanation;
  EXPECT_EQ(first.kind, "stiffness_scale") << d.explanation;
  EXPECT_EQ(first.target, "girders/G3") << d.explanation;
  EXPECT_NEAR(first.parameters[0].value, 0.3, 0.3 * 0.05) << d.explanation;
  EXPECT_GT(first.probability, 0.5) << d.explanation;
  EXPECT_TRUE(first.noise_consistent) << first.reduced_chi2;
  EXPECT_FALSE(first.reduced_model) << "rank 1 is reported from full solves";
  // The screening went through reduced models: far fewer full solves than evaluations.
  EXPECT_LT(d.model_solves, 200) << d.model_solves;
  // The updated model agrees with the test to ≥ 99 %.
  EXPECT_GE(first.mean_agreement_pct, 99.0);
}

// DiagnoseOptions::exact_margin: full solves only for sets that could compete. On this frame the
// reduced models agree with the full solves to a few nats, so the sets hundreds of nats behind
// keep their reduced misfit — fewer full solves, the leading readings unchanged to the digit, and
// every set left unchecked given odds too small to show.
TEST(PartsDiagnosis, SetsFarBehindSkipTheFullSolvesAndLeaveTheLeadersAlone) {
  const model::Model nominal = formats::ReadModelFile(Frame().model);
  const ModeSet test = Measure(
      WithEffects({{EffectKind::kStiffnessScale, EffectTarget::MemberOf("girders", "G3"), {{"factor", 0.3}}, {}, 0}}),
      6, 1e-3, 1);
  DiagnoseOptions every;
  every.exact_margin = std::numeric_limits<double>::infinity();
  const Diagnosis all_checked = Diagnose(nominal, {{"", test}}, every);
  const DiagnoseOptions margin_options;
  const Diagnosis margin = Diagnose(nominal, {{"", test}}, margin_options);
  EXPECT_LT(margin.model_solves, all_checked.model_solves);
  ASSERT_GE(margin.candidates.size(), 3u);
  ASSERT_GE(all_checked.candidates.size(), 3u);
  // Rank 1 is the same full-solve fit either way (its score to the digit); its probability moves
  // only by what the sets left unchecked carried (exact_margin bounds each at e^-7 against it; on
  // this frame they lie far below that).
  const Candidate& a = all_checked.candidates.front();
  const Candidate& b = margin.candidates.front();
  EXPECT_EQ(b.target, a.target);
  EXPECT_FALSE(b.reduced_model);
  EXPECT_NEAR(b.score, a.score, 1e-9 * std::abs(a.score));
  EXPECT_NEAR(b.parameters[0].value, a.parameters[0].value, 1e-12);
  EXPECT_NEAR(b.probability, a.probability, 1e-3);
  int unchecked = 0;
  for (const Candidate& c : margin.candidates)
    if (c.reduced_model) {
      ++unchecked;
      // What the margin promises: more than exact_margin nats behind rank 1 (measured 4e-4 of a
      // probability with OpenBLAS's AVX-512 kernels, below 1e-4 with its Haswell ones).
      EXPECT_LT(c.probability, std::exp(-margin_options.exact_margin) * b.probability) << c.kind << " " << c.target;
    }
  EXPECT_GT(unchecked, 0);
}

// DiagnoseOptions::kept_centres: the reduced-model factories of centres other than the nominal
// one are dropped beyond it (each a factorisation and the probes' responses: gigabytes at 200 000
// DOFs). A centre met again is solved again, deterministically: with one factory kept the
// diagnosis makes more full solves and reports the same candidates, bit for bit.
TEST(PartsDiagnosis, DroppedCentresAreSolvedAgainToTheSameNumbers) {
  const model::Model nominal = formats::ReadModelFile(Frame().model);
  const ModeSet test = Measure(
      WithEffects({{EffectKind::kStiffnessScale, EffectTarget::MemberOf("girders", "G3"), {{"factor", 0.3}}, {}, 0}}),
      6, 1e-3, 1);
  DiagnoseOptions all;
  all.kept_centres = 1000;
  DiagnoseOptions one;
  one.kept_centres = 1;
  const Diagnosis kept = Diagnose(nominal, {{"", test}}, all);
  const Diagnosis dropped = Diagnose(nominal, {{"", test}}, one);
  EXPECT_GT(dropped.model_solves, kept.model_solves) << "no centre was met again: the test shows nothing";
  ASSERT_EQ(dropped.candidates.size(), kept.candidates.size());
  for (size_t i = 0; i < kept.candidates.size(); ++i) {
    EXPECT_EQ(dropped.candidates[i].target, kept.candidates[i].target) << i;
    EXPECT_EQ(dropped.candidates[i].score, kept.candidates[i].score) << i;
    EXPECT_EQ(dropped.candidates[i].probability, kept.candidates[i].probability) << i;
  }
  DiagnoseOptions none;
  none.kept_centres = 0;
  std::string why;
  EXPECT_FALSE(none.IsValid(&why));
  EXPECT_NE(why.find("kept_centres"), std::string::npos) << why;
}

TEST(PartsDiagnosis, OneGroupSoftenedRanksFirst) {
  const model::Model nominal = formats::ReadModelFile(Frame().model);
  const ModeSet test =
      Measure(WithEffects({{EffectKind::kStiffnessScale, EffectTarget::Named("girders"), {{"factor", 0.6}}, {}, 0}}), 6,
              1e-3, 2);
  const Diagnosis d = Diagnose(nominal, {{"", test}});
  const Candidate& first = d.candidates.front();
  ASSERT_EQ(first.effects.size(), 1u) << d.explanation;
  EXPECT_EQ(first.target, "girders") << d.explanation;
  EXPECT_NEAR(first.parameters[0].value, 0.6, 0.6 * 0.1) << d.explanation;
  EXPECT_GE(first.mean_agreement_pct, 99.0);
}

TEST(PartsDiagnosis, APartPlusAnAddedMass) {
  const model::Model nominal = formats::ReadModelFile(Frame().model);
  const ModeSet test =
      Measure(WithEffects({{EffectKind::kStiffnessScale, EffectTarget::Named("bearings"), {{"factor", 0.05}}, {}, 0},
                           {EffectKind::kAddedMass, EffectTarget::Points({1040}), {{"mass", 150.0}}, {}, 0}}),
              6, 5e-4, 3);
  const Diagnosis d = Diagnose(nominal, {{"", test}});
  const Candidate& first = d.candidates.front();
  ASSERT_EQ(first.effects.size(), 2u) << d.explanation;
  EXPECT_EQ(first.kind, "stiffness_scale+added_mass") << d.explanation;
  EXPECT_EQ(first.target, "bearings+points:1040") << d.explanation;
  EXPECT_GE(first.mean_agreement_pct, 99.0);
}

// What no part can express (a spring to ground at mid-span, on FE nodes the vocabulary has no
// effect for): even rank 1 leaves a misfit far above the test's σ, and says so.
TEST(PartsDiagnosis, AMissingEffectNoPartExpressesIsNotNoiseConsistent) {
  model::Model truth = formats::ReadModelFile(Frame().model);
  model::Spring prop;
  prop.name = "prop";
  prop.group = "prop";
  prop.a.node = 1040;
  prop.b.body = model::kGround;
  prop.direction = Eigen::Vector3d::UnitZ();
  prop.law = model::LinearLaw{2e6};
  truth.springs.push_back(prop);
  const model::Model nominal = formats::ReadModelFile(Frame().model);
  const ModeSet test = Measure(truth, 6, 1e-3, 4);
  const Diagnosis d = Diagnose(nominal, {{"", test}});
  EXPECT_FALSE(d.candidates.front().noise_consistent) << d.candidates.front().reduced_chi2 << "\n" << d.explanation;
  EXPECT_GT(d.candidates.front().reduced_chi2, 10.0);
}

}  // namespace
}  // namespace ema::diagnose
