// An effect's target as a typed value (model/effects.hpp, model.hpp EffectTarget): every form read
// from its text by the one reader and written back by the one printer, bad texts refused where
// they are read (the model file's line, DIAG.json's candidate), and the model's names resolved.
#include "ema/model/effects.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "ema/core/error.hpp"
#include "ema/formats/diagnosis_readings.hpp"
#include "ema/formats/model_file.hpp"
#include "test_util.hpp"

namespace ema::model {
namespace {

// What ParseEffectTarget says for `text` ("" when it reads it).
std::string ParseError(EffectKind kind, const std::string& text) {
  std::string error;
  if (ParseEffectTarget(kind, text, &error)) return "";
  return error;
}

struct TargetForm {
  EffectKind kind;
  std::string text;
  EffectTarget typed;
};

TEST(EffectTarget, EveryFormReadsAndPrintsTheSameText) {
  const std::vector<TargetForm> forms = {
      {EffectKind::kSeriesCompliance, "joints", EffectTarget::Named("joints")},              // a spring group
      {EffectKind::kSeriesCompliance, "joints/J3", EffectTarget::MemberOf("joints", "J3")},  // one member
      {EffectKind::kOperatingPoint, "bearings", EffectTarget::Named("bearings")},
      {EffectKind::kStiffnessScale, "girders", EffectTarget::Named("girders")},              // an FE part group
      {EffectKind::kStiffnessScale, "girders/G3", EffectTarget::MemberOf("girders", "G3")},  // one part of it
      {EffectKind::kStiffnessScale, "deck", EffectTarget::Named("deck")},                    // a part in no group
      {EffectKind::kStiffnessScale, "mounts/joint/1",
       EffectTarget::MemberOf("mounts", "joint/1")},  // a member named after its springs
      {EffectKind::kAddedMass, "all_points", EffectTarget::AllPoints()},
      {EffectKind::kAddedMass, "points:101", EffectTarget::Points({101})},
      {EffectKind::kAddedMass, "points:101,102,-3", EffectTarget::Points({101, 102, -3})},
      {EffectKind::kMassScale, "top", EffectTarget::Named("top")},  // a body
      {EffectKind::kMassScale, "deck/P3", EffectTarget::MemberOf("deck", "P3")},
      {EffectKind::kGroundSpring, "base", EffectTarget::Named("base")},
      {EffectKind::kStiffnessScale, "all_points", EffectTarget::Named("all_points")},  // a name for a spring kind
  };
  for (const TargetForm& f : forms) {
    std::string error;
    const std::optional<EffectTarget> read = ParseEffectTarget(f.kind, f.text, &error);
    ASSERT_TRUE(read) << KindName(f.kind) << " '" << f.text << "': " << error;
    EXPECT_EQ(*read, f.typed) << f.text;
    EXPECT_EQ(TargetText(*read), f.text);
    EXPECT_EQ(ParseEffectTarget(f.kind, TargetText(f.typed), nullptr), f.typed) << f.text;
  }
  // The sums over members and points print as DIAG.json always wrote them; no effect is on them.
  EXPECT_EQ(TargetText(EffectTarget::EveryMemberOf("joints")), "joints/*");
  EXPECT_EQ(TargetText(EffectTarget::EveryPoint()), "points:*");
  EXPECT_NE(EffectTarget::Named("joints"), EffectTarget::MemberOf("joints", "J3"));
  EXPECT_NE(EffectTarget::Points({101}), EffectTarget::Points({101, 102}));
  EXPECT_NE(EffectTarget::AllPoints(), EffectTarget::Named("all_points"));
}

TEST(EffectTarget, APointListIsPrintedWithoutTheSpacesItWasReadWith) {
  const std::optional<EffectTarget> t = ParseEffectTarget(EffectKind::kAddedMass, "points: 101 , +102", nullptr);
  ASSERT_TRUE(t);
  EXPECT_EQ(*t, EffectTarget::Points({101, 102}));
  EXPECT_EQ(TargetText(*t), "points:101,102");
}

TEST(EffectTarget, BadTextsAreRefusedSayingWhatWasExpected) {
  const std::string points = "expected 'all_points' or 'points:101,102' (test point ids separated by commas)";
  EXPECT_EQ(ParseError(EffectKind::kAddedMass, "joints"), points);
  EXPECT_EQ(ParseError(EffectKind::kAddedMass, "points:"), "bad point id '': " + points);
  EXPECT_EQ(ParseError(EffectKind::kAddedMass, "points:1,,2"), "bad point id '': " + points);
  EXPECT_EQ(ParseError(EffectKind::kAddedMass, "points:101,"), "bad point id '': " + points);
  EXPECT_EQ(ParseError(EffectKind::kAddedMass, "points:1x"), "bad point id '1x': " + points);
  EXPECT_EQ(ParseError(EffectKind::kAddedMass, "points:*"), "bad point id '*': " + points);
  EXPECT_EQ(ParseError(EffectKind::kAddedMass, "points:99999999999"), "bad point id '99999999999': " + points);
  const std::string springs = "expected a spring group ('joints') or one member of it ('joints/J3')";
  EXPECT_EQ(ParseError(EffectKind::kSeriesCompliance, ""), springs);
  EXPECT_EQ(ParseError(EffectKind::kSeriesCompliance, "joints/"), "no one member after '/': " + springs);
  EXPECT_EQ(ParseError(EffectKind::kOperatingPoint, "joints/*"), "no one member after '/': " + springs);
  EXPECT_EQ(ParseError(EffectKind::kSeriesCompliance, "/J3"), "no group before '/': " + springs);
  EXPECT_EQ(ParseError(EffectKind::kGroundSpring, "top/lid"), "a body's name has no '/': expected a body ('top')");
  EXPECT_NE(ParseError(EffectKind::kStiffnessScale, "").find("FE part group"), std::string::npos);
  EXPECT_NE(ParseError(EffectKind::kMassScale, "").find("a body, an FE part group"), std::string::npos);
}

// A one-body model with a spring group and two test points, and `effect` (TOML) appended.
std::filesystem::path ModelWithEffect(const std::string& name, const std::string& effect) {
  return testing::WriteText(testing::TempDir(name) / "m.toml", R"([[body]]
name = "top"
mass = 1.0
inertia = [0.01, 0.01, 0.01]

[[spring]]
name = "J1"
group = "joints"
a = { body = "top", at = [0.1, 0.0, 0.0] }
direction = "+Z"
law = { linear = { k = 1e6 } }

[[point]]
id = 101
body = "top"
at = [0.1, 0.0, 0.0]

[[point]]
id = 102
body = "top"
at = [-0.1, 0.0, 0.0]

)" + effect);
}

// The message of the InputError reading `path` throws ("" when none).
std::string ReadError(const std::filesystem::path& path) {
  try {
    formats::ReadModelFile(path);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(EffectTarget, ABadTargetIsSaidAtItsFileAndLine) {
  const auto bad_id =
      ModelWithEffect("target_bad_id", "[[effect]]\nkind = \"added_mass\"\ntarget = \"points:101,x\"\nmass = 0.1\n");
  EXPECT_EQ(ReadError(bad_id), bad_id.string() +
                                   ":25: effect added_mass 'points:101,x': bad point id 'x': expected "
                                   "'all_points' or 'points:101,102' (test point ids separated by commas)");
  const auto every =
      ModelWithEffect("target_every", "[[effect]]\nkind = \"stiffness_scale\"\ntarget = \"joints/*\"\nfactor = 2.0\n");
  EXPECT_EQ(ReadError(every), every.string() +
                                  ":25: effect stiffness_scale 'joints/*': no one member after '/': expected "
                                  "a spring group or FE part group ('joints'), one member of it ('joints/J3'), "
                                  "or a part in no group");
  // DIAG.json's effects are read by the same reader: the candidate is named instead of a line.
  const auto dir = testing::TempDir("target_diag");
  const auto diag = testing::WriteText(dir / "DIAG.json", R"({"candidates": [{"rank": 1, "kind": "added_mass",
    "target": "points:", "effects": [{"kind": "added_mass", "target": "points:", "parameters": {"mass": 0.1}}]}]})");
  try {
    formats::ReadDiagnosisReadings(diag);
    FAIL() << "a bad target in DIAG.json was read";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), diag.string() +
                                         ": candidate rank 1: effect 1: effect added_mass 'points:': bad "
                                         "point id '': expected 'all_points' or 'points:101,102' (test "
                                         "point ids separated by commas)");
  }
}

TEST(EffectTarget, WhatTheWriterWritesTheReaderReadsAsTheSameTarget) {
  const std::vector<Effect> effects = {
      {EffectKind::kStiffnessScale, EffectTarget::MemberOf("joints", "J1"), {{"factor", 0.5}}, std::nullopt, 0},
      {EffectKind::kAddedMass, EffectTarget::Points({101, 102}), {{"mass", 0.01}}, std::nullopt, 0},
      {EffectKind::kAddedMass, EffectTarget::AllPoints(), {{"mass", 0.01}}, std::nullopt, 0},
      {EffectKind::kMassScale, EffectTarget::Named("top"), {{"factor", 1.1}}, std::nullopt, 0},
      {EffectKind::kSeriesCompliance, EffectTarget::Named("joints"), {{"k", 5e6}}, std::nullopt, 0},
  };
  std::string text;
  for (const Effect& e : effects) text += formats::EffectToToml(e) + "\n";
  EXPECT_NE(text.find("target = \"points:101,102\"\n"), std::string::npos) << text;
  const Model read = formats::ReadModelFile(ModelWithEffect("target_round_trip", text));
  ASSERT_EQ(read.effects.size(), effects.size());
  for (std::size_t i = 0; i < effects.size(); ++i) {
    EXPECT_EQ(read.effects[i].kind, effects[i].kind);
    EXPECT_EQ(read.effects[i].target, effects[i].target) << TargetText(effects[i].target);
  }
  EXPECT_EQ(Describe(effects[1]), "added_mass points:101,102 mass=0.01");
}

TEST(EffectTarget, TheModelSaysWhatANameIs) {
  const Model m = formats::ReadModelFile(ModelWithEffect("target_resolve", ""));
  EXPECT_EQ(TargetSprings(m, EffectTarget::Named("joints")), std::vector<int>{0});
  EXPECT_EQ(TargetSprings(m, EffectTarget::MemberOf("joints", "J1")), std::vector<int>{0});
  EXPECT_TRUE(TargetSprings(m, EffectTarget::Named("top")).empty());
  EXPECT_TRUE(TargetSprings(m, EffectTarget::EveryMemberOf("joints")).empty());  // a sum, not a target
  ASSERT_NE(TargetBody(m, EffectTarget::Named("top")), nullptr);
  EXPECT_EQ(TargetBody(m, EffectTarget::Named("joints")), nullptr);
  Effect e{EffectKind::kAddedMass, EffectTarget::Points({102, 101}), {{"mass", 0.01}}, std::nullopt, 0};
  EXPECT_EQ(TargetPoints(m, e), (std::vector<int>{1, 0}));
  e.target = EffectTarget::AllPoints();
  EXPECT_EQ(TargetPoints(m, e), (std::vector<int>{0, 1}));
  e.target = EffectTarget::Points({103});
  EXPECT_THROW(TargetPoints(m, e), InputError);
}

TEST(EffectTarget, NamesThatWouldReadAsAnotherTargetAreRefused) {
  // '/' separates a group from its member, so a body or spring group named with one could not be
  // targeted; the reader says so at the name.
  const auto dir = testing::TempDir("target_names");
  const auto body =
      testing::WriteText(dir / "body.toml", "[[body]]\nname = \"top/lid\"\nmass = 1.0\ninertia = [0.01, 0.01, 0.01]\n");
  EXPECT_NE(ReadError(body).find(body.string() + ":2: [[body]]: name 'top/lid' has a '/'"), std::string::npos)
      << ReadError(body);
  const auto spring = testing::WriteText(dir / "spring.toml", R"([[body]]
name = "top"
mass = 1.0
inertia = [0.01, 0.01, 0.01]

[[spring]]
name = "mount 1/2"
a = { body = "top" }
direction = "+Z"
law = { linear = { k = 1e6 } }
)");
  EXPECT_NE(ReadError(spring).find(spring.string() +
                                   ":7: spring 'mount 1/2': a spring without 'group' is a group of its own"),
            std::string::npos)
      << ReadError(spring);
}

}  // namespace
}  // namespace ema::model
