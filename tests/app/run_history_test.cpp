// The history of `ema run`s in one output folder and the diagnosed places (app/run_history.hpp).
#include "ema/formats/model_file.hpp"
#include "report.hpp"
#include "run_history.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

using ema::model::EffectTarget;

namespace ema::app {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

const fs::path kDir = fs::path(EMA_TEST_TMP_DIR) / ("run-history-" + std::to_string(getpid()));

const char* kModel = R"(
[[body]]
name = "top"
mass = 2.0
inertia = [0.01, 0.01, 0.01]
centre = [0.0, 0.0, 0.05]

[[spring]]
name = "J1X"
group = "joints"
a = { body = "top", at = [0.1, 0.0, 0.0] }
direction = [1, 0, 0]
law = { linear = { k = 1.0e7 } }

[[spring]]
name = "J1Z"
group = "joints"
a = { body = "top", at = [0.1, 0.0, 0.0] }
direction = [0, 0, 1]
law = { linear = { k = 1.0e7 } }

[[spring]]
name = "J2Z"
group = "joints"
a = { body = "top", at = [-0.1, 0.0, 0.0] }
direction = [0, 0, 1]
law = { linear = { k = 1.0e7 } }

[[point]]
id = 101
body = "top"
at = [0.0, 0.05, 0.1]
)";

TEST(RunHistory, EachRunAppendsAVersionWithItsEffectsHashAndAgreement) {
  fs::remove_all(kDir);
  fs::create_directories(kDir);
  const fs::path model = kDir / "model.toml";
  std::ofstream(model) << kModel;
  RunRecord r;
  r.stamp = "2026-11-23T12:00:00Z";
  r.model = model;
  r.agreement_before = 80.0;
  r.agreement_after = 99.0;
  r.mac_before = 0.9;
  r.mac_after = 0.99;
  r.rank_one = RunRecord::RankOne{"stiffness_scale", "joints/J1", 0.9};
  json h = AppendRunHistory(kDir, r);
  ASSERT_EQ(h.size(), 1u);
  EXPECT_EQ(h[0]["version"], 1);
  EXPECT_TRUE(h[0]["effects"].empty());
  const std::string first_hash = h[0]["hash"];
  EXPECT_EQ(first_hash.size(), 16u);
  EXPECT_EQ(h[0]["diagnosis"]["target"], "joints/J1");
  // The engineer adds the diagnosed effect and runs again: a second version, another hash.
  std::ofstream(model, std::ios::app) << "\n[[effect]]\nkind = \"stiffness_scale\"\ntarget = \"joints/J1\"\nfactor = 0.3\n";
  r.agreement_before = 99.0;
  h = AppendRunHistory(kDir, r);
  ASSERT_EQ(h.size(), 2u);
  EXPECT_EQ(h[1]["version"], 2);
  EXPECT_NE(h[1]["hash"], first_hash);
  ASSERT_EQ(h[1]["effects"].size(), 1u);
  EXPECT_NE(h[1]["effects"][0].get<std::string>().find("stiffness_scale joints/J1"), std::string::npos);
  EXPECT_DOUBLE_EQ(h[1]["mean_agreement_pct_before"].get<double>(), 99.0);
  // The file on disk holds both.
  std::ifstream in(kDir / "history.json");
  EXPECT_EQ(json::parse(in).size(), 2u);
}

TEST(RunHistory, DiagnosedMemberIsPlacedAtItsSpringEnds) {
  fs::create_directories(kDir);
  const fs::path model = kDir / "places.toml";
  std::ofstream(model) << kModel;
  const model::Model m = formats::ReadModelFile(model);
  auto effect = [](model::EffectKind kind, const EffectTarget& target) {
    model::Effect e;
    e.kind = kind;
    e.target = target;
    return e;
  };
  const json places =
      report::DiagnosedPlaces(m, {effect(model::EffectKind::kStiffnessScale, EffectTarget::MemberOf("joints", "J1")),
                                  effect(model::EffectKind::kAddedMass, EffectTarget::Points({101})),
                                  effect(model::EffectKind::kMassScale, EffectTarget::Named("top"))});
  ASSERT_EQ(places.size(), 3u);
  EXPECT_EQ(places[0]["label"], "J1");
  // J1X and J1Z: end a at (0.1, 0, 0) each; end b is ground (not drawn).
  ASSERT_EQ(places[0]["points"].size(), 2u);
  EXPECT_DOUBLE_EQ(places[0]["points"][0][0].get<double>(), 0.1);
  ASSERT_EQ(places[1]["points"].size(), 1u);
  EXPECT_DOUBLE_EQ(places[1]["points"][0][2].get<double>(), 0.1);
  EXPECT_DOUBLE_EQ(places[2]["points"][0][2].get<double>(), 0.05);  // the body's centre
  EXPECT_TRUE(report::DiagnosedPlaces(m, {}).empty());  // rank 1 "none": nothing to draw
}

}  // namespace
}  // namespace ema::app
