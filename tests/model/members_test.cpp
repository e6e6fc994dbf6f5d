// Members of spring groups (model-format.md "Members"), member targets of effects, the typed
// effect table, and the prior-knowledge keys of the model file ("Prior knowledge").
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "ema/core/error.hpp"
#include "ema/formats/model_file.hpp"
#include "ema/model/effects.hpp"
#include "ema/model/solve.hpp"
#include "test_util.hpp"

using ema::model::EffectTarget;

namespace ema::model {
namespace {

using testing::MakeBody;
using testing::MakeSpring;

// Two bodies joined by joints J1 (springs J1X, J1Y at one point), J2 (J2X, J2Y at another),
// and "bolt"/"stud" at a third point sharing no prefix; plus two mounts to ground.
Model Joints() {
  Model m;
  m.bodies = {MakeBody("top", 2.0, {0.01, 0.01, 0.01}, {0, 0, 0.05}), MakeBody("base", 5.0, {0.05, 0.05, 0.05})};
  auto joint = [&](const std::string& name, Eigen::Vector3d at, Eigen::Vector3d dir) {
    Spring s = MakeSpring(name, "joints", "top", at, dir, Law(LinearLaw{1e7}));
    s.b.body = "base";
    m.springs.push_back(s);
  };
  joint("J1X", {0.1, 0, 0}, Eigen::Vector3d::UnitX());
  joint("J1Y", {0.1, 0, 0}, Eigen::Vector3d::UnitY());
  joint("J2X", {-0.1, 0, 0}, Eigen::Vector3d::UnitX());
  joint("J2Y", {-0.1, 0, 0}, Eigen::Vector3d::UnitY());
  joint("bolt", {0, 0.1, 0}, Eigen::Vector3d::UnitZ());
  joint("stud", {0, 0.1, 0}, Eigen::Vector3d::UnitX());
  for (double x : {-0.1, 0.1}) {
    Spring s = MakeSpring(x < 0 ? "MZ1" : "MZ2", "mounts", "base", {x, 0, -0.1}, Eigen::Vector3d::UnitZ(), Law(LinearLaw{5e6}));
    s.b.body = kGround;
    m.springs.push_back(s);
  }
  Spring lateral = MakeSpring("lat", "mounts", "base", {0, 0, -0.1}, Eigen::Vector3d::UnitX(), Law(LinearLaw{5e6}));
  lateral.b.body = kGround;
  m.springs.push_back(lateral);
  Spring lateral_y = lateral;
  lateral_y.name = "laty";
  lateral_y.direction = Eigen::Vector3d::UnitY();
  m.springs.push_back(lateral_y);
  Spring tz = lateral;
  tz.name = "torsion";
  tz.direction = Eigen::Vector3d::UnitZ();
  tz.a.at = {0.05, 0.05, -0.1};
  m.springs.push_back(tz);
  return m;
}

TEST(Members, SameTwoPointsFormOneMemberNamedByCommonPrefix) {
  const std::vector<Member> members = Members(Joints());
  ASSERT_EQ(members.size(), 7u);
  EXPECT_EQ(members[0].Target(), EffectTarget::MemberOf("joints", "J1"));
  EXPECT_EQ(members[0].springs, (std::vector<int>{0, 1}));
  EXPECT_EQ(members[1].Target(), EffectTarget::MemberOf("joints", "J2"));
  // "bolt" and "stud" share no prefix: the first spring's name.
  EXPECT_EQ(members[2].Target(), EffectTarget::MemberOf("joints", "bolt"));
  EXPECT_EQ(members[2].springs, (std::vector<int>{4, 5}));
  // Single springs keep their own name; "lat"+"laty" share the prefix "lat".
  EXPECT_EQ(members[3].Target(), EffectTarget::MemberOf("mounts", "MZ1"));
  EXPECT_EQ(members[4].Target(), EffectTarget::MemberOf("mounts", "MZ2"));
  EXPECT_EQ(members[5].Target(), EffectTarget::MemberOf("mounts", "lat"));
  EXPECT_EQ(members[5].springs, (std::vector<int>{8, 9}));
  // "torsion" sits at its own point: a member of its own.
  EXPECT_EQ(members[6].Target(), EffectTarget::MemberOf("mounts", "torsion"));
}

TEST(Members, ExplicitMemberKeyWinsAndPrefixCollisionsFallBackToTheFirstName) {
  Model m = Joints();
  // J1X/J1Y and J2X/J2Y renamed so both pairs share the prefix "J": not unique → first names.
  m.springs[0].name = "JAX";
  m.springs[1].name = "JAY";
  m.springs[2].name = "JBX";
  m.springs[3].name = "JBY";
  for (int i : {2, 3}) m.springs[i].name = "JA" + std::string(1, "XY"[i - 2]) + "2";
  // An explicit key groups springs at different points.
  m.springs[4].member = "anchor";
  m.springs[8].member = "anchor";  // "lat" in mounts: another group, so another member
  const std::vector<Member> members = Members(m);
  std::vector<std::string> names;
  for (const Member& x : members) names.push_back(TargetText(x.Target()));
  // JAX+JAY → prefix "JA"; JAX2+JAY2 → prefix "JA" too: both fall back to the first spring's name.
  EXPECT_EQ(names[0], "joints/JAX");
  EXPECT_EQ(names[1], "joints/JAX2");
  EXPECT_NE(std::find(names.begin(), names.end(), "joints/anchor"), names.end());
  EXPECT_NE(std::find(names.begin(), names.end(), "mounts/anchor"), names.end());
  EXPECT_EQ(TargetSprings(m, EffectTarget::MemberOf("joints", "anchor")), std::vector<int>{4});
}

TEST(Members, MemberEffectChangesOnlyThatMember) {
  const Model m = Joints();
  const Model scaled = ApplyEffect(
      m,
      Effect{EffectKind::kStiffnessScale, EffectTarget::MemberOf("joints", "J2"), {{"factor", 0.25}}, std::nullopt, 0});
  for (size_t i = 0; i < m.springs.size(); ++i)
    EXPECT_DOUBLE_EQ(scaled.springs[i].stiffness_factor, (i == 2 || i == 3) ? 0.25 : 1.0) << m.springs[i].name;
  const Model series = ApplyEffect(
      m, Effect{EffectKind::kSeriesCompliance, EffectTarget::MemberOf("joints", "J1"), {{"k", 1e7}}, std::nullopt, 0});
  // Two 1e7 springs in series: 5e6 for J1's springs, unchanged elsewhere.
  EXPECT_NEAR(LinearizeLaw(series.springs[0].law, "J1X").stiffness, 5e6, 1e-3);
  EXPECT_NEAR(LinearizeLaw(series.springs[2].law, "J2X").stiffness, 1e7, 1e-3);
  try {
    ApplyEffect(
        m,
        Effect{
            EffectKind::kStiffnessScale, EffectTarget::MemberOf("joints", "J9"), {{"factor", 0.5}}, std::nullopt, 0});
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("no member 'J9' in group 'joints' (members: J1, J2, bolt)"), std::string::npos)
        << e.what();
  }
}

TEST(EffectTable, EveryKindOnceWithItsParameterAndAnApplyFunction) {
  const auto& table = EffectKindTable();
  ASSERT_EQ(table.size(), 6u);
  EXPECT_EQ(EffectKinds(), (std::vector<std::string>{"series_compliance", "stiffness_scale", "operating_point",
                                                     "added_mass", "mass_scale", "ground_spring"}));
  for (const EffectKindInfo& info : table) {
    EXPECT_EQ(&Info(info.kind), &info);
    EXPECT_EQ(FindEffectKind(info.name), &info);
    EXPECT_NE(info.apply, nullptr);
    EXPECT_LT(info.range_low, info.range_high);
    EXPECT_GT(info.prior_sigma, 0.0);
  }
  EXPECT_EQ(FindEffectKind("glue"), nullptr);
  EXPECT_STREQ(Info(EffectKind::kMassScale).parameter, "factor");
  EXPECT_DOUBLE_EQ(Info(EffectKind::kMassScale).prior_sigma, 0.05);  // documented default (docs/diagnose.md)
}

TEST(EffectTable, AnUnknownKindIsSaidWhereTheModelFileIsRead) {
  // The kind is parsed once, by the reader, with the words applying the effect used to say.
  const auto dir = testing::TempDir("effect_kind_unknown");
  const auto path = testing::WriteText(dir / "m.toml", "[[body]]\nname = \"c\"\nmass = 1.0\ninertia = [0.01, 0.01, 0.01]\n"
                                                       "\n[[effect]]\nkind = \"glue\"\ntarget = \"c\"\nfactor = 2.0\n");
  try {
    formats::ReadModelFile(path);
    FAIL() << "an unknown effect kind was read";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), path.string() + ":6: effect glue 'c': unknown effect kind (allowed: series_compliance, "
                                                      "stiffness_scale, operating_point, added_mass, mass_scale, ground_spring)");
  }
}

TEST(PriorKnowledge, UncertaintyMemberAndPriorsAreRead) {
  const auto dir = testing::TempDir("prior_knowledge");
  const auto path = testing::WriteText(dir / "m.toml", R"(
[[body]]
name = "carriage"
mass = 2.88
inertia = [0.01, 0.01, 0.01]
uncertainty = 0.02

[[spring]]
name = "B1"
group = "bearings"
member = "pad-1"
a = { body = "carriage", at = [0.1, 0, 0] }
direction = [0, 0, 1]
law = { linear = { k = 2.0e7 } }
uncertainty = 0.5

[priors]
mass_scale = 0.1
added_mass = 0.01
)");
  const Model m = formats::ReadModelFile(path);
  EXPECT_DOUBLE_EQ(m.bodies[0].uncertainty, 0.02);
  EXPECT_DOUBLE_EQ(m.springs[0].uncertainty, 0.5);
  EXPECT_EQ(m.springs[0].member, "pad-1");
  EXPECT_EQ(Members(m).front().Target(), EffectTarget::MemberOf("bearings", "pad-1"));
  EXPECT_DOUBLE_EQ(m.priors.at(EffectKind::kMassScale), 0.1);
  EXPECT_DOUBLE_EQ(m.priors.at(EffectKind::kAddedMass), 0.01);
  EXPECT_EQ(m.priors.count(EffectKind::kStiffnessScale), 0u);
}

TEST(PriorKnowledge, BadValuesAreInputErrorsNamingTheKey) {
  const auto dir = testing::TempDir("prior_knowledge_bad");
  const std::string body = "[[body]]\nname = \"c\"\nmass = 1.0\ninertia = [0.01, 0.01, 0.01]\n";
  const auto unknown = testing::WriteText(dir / "a.toml", body + "\n[priors]\nglue = 0.1\n");
  try {
    formats::ReadModelFile(unknown);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("glue"), std::string::npos) << e.what();
  }
  const auto negative = testing::WriteText(dir / "b.toml", body + "uncertainty = -0.1\n");
  EXPECT_THROW(formats::ReadModelFile(negative), InputError);
  const auto zero = testing::WriteText(dir / "c.toml", body + "\n[priors]\nmass_scale = 0\n");
  EXPECT_THROW(formats::ReadModelFile(zero), InputError);
}

TEST(PriorKnowledge, FaultTailOfStiffnessPriorsFromTheModelFile) {
  // model-format.md, added turn 4: [priors] stiffness_fault_share and stiffness_fault_width.
  const auto dir = testing::TempDir("prior_fault_tail");
  const std::string body = "[[body]]\nname = \"c\"\nmass = 1.0\ninertia = [0.01, 0.01, 0.01]\n";
  const Model given = formats::ReadModelFile(
      testing::WriteText(dir / "given.toml", body + "\n[priors]\nstiffness_fault_share = 0.1\nstiffness_fault_width = 2.0\n"));
  EXPECT_DOUBLE_EQ(given.stiffness_fault_share.value_or(-1.0), 0.1);
  EXPECT_DOUBLE_EQ(given.stiffness_fault_width.value_or(-1.0), 2.0);
  const Model off = formats::ReadModelFile(testing::WriteText(dir / "off.toml", body + "\n[priors]\nstiffness_fault_share = 0\n"));
  EXPECT_DOUBLE_EQ(off.stiffness_fault_share.value_or(-1.0), 0.0);
  EXPECT_FALSE(off.stiffness_fault_width.has_value());
  const Model none = formats::ReadModelFile(testing::WriteText(dir / "none.toml", body));
  EXPECT_FALSE(none.stiffness_fault_share.has_value());
  // Out of range: named with the key, the line and what was expected.
  for (const std::string bad : {"stiffness_fault_share = 1.0", "stiffness_fault_share = -0.1", "stiffness_fault_share = \"a\"",
                                "stiffness_fault_width = 0", "stiffness_fault_width = -3.0"}) {
    const auto path = testing::WriteText(dir / "bad.toml", body + "\n[priors]\n" + bad + "\n");
    try {
      formats::ReadModelFile(path);
      ADD_FAILURE() << bad;
    } catch (const InputError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("bad.toml:7"), std::string::npos) << what;
      EXPECT_NE(what.find(bad.substr(0, bad.find(' '))), std::string::npos) << what;
    }
  }
}

}  // namespace
}  // namespace ema::model
