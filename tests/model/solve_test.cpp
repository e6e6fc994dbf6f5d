// Assembly and eigen solution against closed forms; effects as exact changes of M and K.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>

#include "ema/core/error.hpp"
#include "ema/model/effects.hpp"
#include "ema/model/solve.hpp"
#include "test_util.hpp"

using ema::model::EffectTarget;

namespace ema::model {
namespace {

using testing::MakeBody;
using testing::MakeSpring;

/// Ground -k1- body1 -k2- body2 along X (springs at the body centres).
Model TwoDof(double m1, double m2, double k1, double k2) {
  Model m;
  m.name = "2dof";
  m.bodies = {MakeBody("b1", m1, {1e-3, 1e-3, 1e-3}), MakeBody("b2", m2, {2e-3, 2e-3, 2e-3}, {1.0, 0.0, 0.0})};
  m.springs.push_back(MakeSpring("k1", "g1", "b1", {0, 0, 0}, Eigen::Vector3d::UnitX(), LinearLaw{k1}));
  Spring s2 = MakeSpring("k2", "g2", "b2", {1.0, 0, 0}, Eigen::Vector3d::UnitX(), LinearLaw{k2});
  s2.b.body = "b1";
  s2.b.has_at = false;  // b.at defaults to a.at
  m.springs.push_back(s2);
  TestPoint p1, p2;
  p1.id = 1, p1.where.body = "b1";
  p2.id = 2, p2.where.body = "b2";
  m.points = {p1, p2};
  m.damping.ratios = {0.01, 0.02};
  return m;
}

TEST(Solve, TwoDofMatchesClosedForm) {
  const double m1 = 2.0, m2 = 1.0, k1 = 3e5, k2 = 1e5;
  const Solution sol = Solve(TwoDof(m1, m2, k1, k2));
  // det(K - w^2 M) = 0: m1 m2 w^4 - (m1 k2 + m2 (k1 + k2)) w^2 + k1 k2 = 0.
  const double a = m1 * m2, b = -(m1 * k2 + m2 * (k1 + k2)), c = k1 * k2;
  const double w1 = std::sqrt((-b - std::sqrt(b * b - 4 * a * c)) / (2 * a));
  const double w2 = std::sqrt((-b + std::sqrt(b * b - 4 * a * c)) / (2 * a));
  EXPECT_EQ(sol.rigid_body_frequencies_hz.size(), 10u) << "5 unrestrained DOF per body";
  ASSERT_EQ(sol.modes.modes.size(), 2u);
  EXPECT_NEAR(sol.modes.modes[0].frequency_hz, w1 / kTwoPi, 1e-9 * w1);
  EXPECT_NEAR(sol.modes.modes[1].frequency_hz, w2 / kTwoPi, 1e-9 * w2);
  EXPECT_DOUBLE_EQ(sol.modes.modes[0].damping_ratio, 0.01);
  EXPECT_DOUBLE_EQ(sol.modes.modes[1].damping_ratio, 0.02);
  // Mode shape ratio x2/x1 = k2 / (k2 - m2 w^2) from the second row; unit modal mass
  // m1 x1^2 + m2 x2^2 = 1. Shapes are at the test points' +X DOF (rows 0 and 3).
  for (int j = 0; j < 2; ++j) {
    const double w = j == 0 ? w1 : w2;
    const auto& shape = sol.modes.modes[j].shape;
    const double x1 = shape[0].real(), x2 = shape[3].real();
    EXPECT_NEAR(x2 / x1, k2 / (k2 - m2 * w * w), 1e-8);
    EXPECT_NEAR(m1 * x1 * x1 + m2 * x2 * x2, 1.0, 1e-9);
    EXPECT_TRUE(sol.modes.modes[j].unit_modal_mass);
  }
  EXPECT_EQ(sol.modes.dofs.size(), 6u);
  EXPECT_EQ(sol.modes.dofs[3], (Dof{2, 1}));
}

TEST(Solve, SetupOverridesOperatingPointByGroup) {
  Model m = TwoDof(1.0, 1.0, 1e5, 1e5);
  AirFilmLaw film;
  film.gap = {2e-6, 4e-6, 6e-6, 8e-6, 10e-6};
  film.load = {500.0, 300.0, 180.0, 110.0, 70.0};
  film.operating_gap = 4e-6;
  m.springs[0].law = film;
  m.setups.push_back(model::Setup{"wide", {{"g1", 8e-6}}, 0});
  const System nominal = Assemble(m);
  SolveOptions o;
  o.setup = "wide";
  const System wide = Assemble(m, o);
  EXPECT_NEAR(nominal.springs[0].gap, 4e-6, 1e-18);
  EXPECT_NEAR(wide.springs[0].gap, 8e-6, 1e-18);
  EXPECT_LT(wide.springs[0].stiffness, nominal.springs[0].stiffness);
  o.setup = "missing";
  EXPECT_THROW(Assemble(m, o), InputError);
}

// --- effects: each changes M or K exactly as its formula says --------------------------------

Model OneBody() {
  Model m;
  m.bodies = {MakeBody("c", 3.0, {0.01, 0.02, 0.03}, {0.1, 0.0, 0.0})};
  m.springs.push_back(MakeSpring("s1", "bearings", "c", {0.2, 0.05, 0.0}, {0, 0, 1}, LinearLaw{2e6}));
  m.springs.push_back(MakeSpring("s2", "mounts", "c", {0.0, -0.05, 0.0}, {0, 1, 0}, LinearLaw{1e6}));
  TestPoint p;
  p.id = 101;
  p.where.body = "c";
  p.where.at = {0.3, 0.1, 0.05};
  p.where.has_at = true;
  m.points = {p};
  return m;
}

/// Constraint row of a translational spring at r (relative to the centre) along n.
Eigen::VectorXd SpringRow(const Eigen::Vector3d& r, const Eigen::Vector3d& n) {
  Eigen::VectorXd g(6);
  g << n, r.cross(n);  // n . (u0 + theta x r) = n . u0 + theta . (r x n)
  return g;
}

Eigen::MatrixXd Dense(const Eigen::SparseMatrix<double>& a) { return Eigen::MatrixXd(a); }

TEST(Effects, StiffnessScaleScalesGroupStiffness) {
  const Model m = OneBody();
  const Model e = ApplyEffect(
      m, Effect{EffectKind::kStiffnessScale, EffectTarget::Named("bearings"), {{"factor", 1.5}}, std::nullopt, 0});
  const Eigen::VectorXd g = SpringRow(Eigen::Vector3d(0.1, 0.05, 0.0), Eigen::Vector3d::UnitZ());
  const Eigen::MatrixXd dk = Dense(Assemble(e).stiffness) - Dense(Assemble(m).stiffness);
  EXPECT_LT((dk - 0.5 * 2e6 * g * g.transpose()).cwiseAbs().maxCoeff(), 1e-6);
}

TEST(Effects, SeriesComplianceGivesSeriesStiffness) {
  const Model m = OneBody();
  const Model e = ApplyEffect(
      m, Effect{EffectKind::kSeriesCompliance, EffectTarget::Named("bearings"), {}, Law(LinearLaw{6e6}), 0});
  const double k_new = 1.0 / (1.0 / 2e6 + 1.0 / 6e6);
  const Eigen::VectorXd g = SpringRow(Eigen::Vector3d(0.1, 0.05, 0.0), Eigen::Vector3d::UnitZ());
  const Eigen::MatrixXd dk = Dense(Assemble(e).stiffness) - Dense(Assemble(m).stiffness);
  EXPECT_LT((dk - (k_new - 2e6) * g * g.transpose()).cwiseAbs().maxCoeff(), 1e-6);
  EXPECT_EQ(Assemble(e).springs[1].stiffness, 1e6) << "other groups untouched";
}

TEST(Effects, SeriesComplianceAcceptsKParameterAsLinearLaw) {
  const Model m = OneBody();
  const Model by_law = ApplyEffect(
      m, Effect{EffectKind::kSeriesCompliance, EffectTarget::Named("bearings"), {}, Law(LinearLaw{6e6}), 0});
  const Model by_k = ApplyEffect(
      m, Effect{EffectKind::kSeriesCompliance, EffectTarget::Named("bearings"), {{"k", 6e6}}, std::nullopt, 0});
  EXPECT_DOUBLE_EQ(Assemble(by_k).springs[0].stiffness, Assemble(by_law).springs[0].stiffness);
}

TEST(Effects, OperatingPointMovesTheAirGap) {
  Model m = OneBody();
  AirFilmLaw film;
  film.gap = {2e-6, 4e-6, 6e-6, 8e-6};
  film.load = {400.0, 250.0, 160.0, 100.0};
  film.operating_gap = 4e-6;
  m.springs[0].law = film;
  const Model e = ApplyEffect(
      m, Effect{EffectKind::kOperatingPoint, EffectTarget::Named("bearings"), {{"value", 6e-6}}, std::nullopt, 0});
  const SpringState direct = LinearizeLaw(film, "t", 6e-6);
  EXPECT_DOUBLE_EQ(Assemble(e).springs[0].stiffness, direct.stiffness);
  EXPECT_THROW(
      ApplyEffect(
          m, Effect{EffectKind::kOperatingPoint, EffectTarget::Named("mounts"), {{"value", 1.0}}, std::nullopt, 0}),
      InputError)
      << "a linear-only group has no operating point";
}

TEST(Effects, AddedMassAtPointIsRigidBodyMassMatrixOfThePoint) {
  const Model m = OneBody();
  const Model e =
      ApplyEffect(m, Effect{EffectKind::kAddedMass, EffectTarget::Points({101}), {{"mass", 0.02}}, std::nullopt, 0});
  const Eigen::Vector3d r = Eigen::Vector3d(0.3, 0.1, 0.05) - Eigen::Vector3d(0.1, 0, 0);
  Eigen::MatrixXd t(3, 6);  // u = [I, -[r]x] q
  Eigen::Matrix3d rx;
  rx << 0, -r.z(), r.y(), r.z(), 0, -r.x(), -r.y(), r.x(), 0;
  t << Eigen::Matrix3d::Identity(), -rx;
  const Eigen::MatrixXd dm = Dense(Assemble(e).mass) - Dense(Assemble(m).mass);
  EXPECT_LT((dm - 0.02 * t.transpose() * t).cwiseAbs().maxCoeff(), 1e-15);
  const Model all =
      ApplyEffect(m, Effect{EffectKind::kAddedMass, EffectTarget::AllPoints(), {{"mass", 0.02}}, std::nullopt, 0});
  EXPECT_LT((Dense(Assemble(all).mass) - Dense(Assemble(e).mass)).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_THROW(
      ApplyEffect(m, Effect{EffectKind::kAddedMass, EffectTarget::Points({999}), {{"mass", 0.02}}, std::nullopt, 0}),
      InputError);
}

TEST(Effects, MassScaleScalesBodyMassAndInertia) {
  const Model m = OneBody();
  const Model e =
      ApplyEffect(m, Effect{EffectKind::kMassScale, EffectTarget::Named("c"), {{"factor", 1.2}}, std::nullopt, 0});
  EXPECT_LT((Dense(Assemble(e).mass) - 1.2 * Dense(Assemble(m).mass)).cwiseAbs().maxCoeff(), 1e-15);
  // Frequencies scale with 1/sqrt(factor).
  const double f0 = Solve(m).modes.modes[0].frequency_hz, f1 = Solve(e).modes.modes[0].frequency_hz;
  EXPECT_NEAR(f1, f0 / std::sqrt(1.2), 1e-9 * f0);
}

TEST(Effects, GroundSpringAddsTranslationalStiffnessAtCentre) {
  const Model m = OneBody();
  const Model e =
      ApplyEffect(m, Effect{EffectKind::kGroundSpring, EffectTarget::Named("c"), {{"k", 5e4}}, std::nullopt, 0});
  Eigen::MatrixXd expected = Eigen::MatrixXd::Zero(6, 6);
  expected.topLeftCorner(3, 3) = 5e4 * Eigen::Matrix3d::Identity();
  EXPECT_LT((Dense(Assemble(e).stiffness) - Dense(Assemble(m).stiffness) - expected).cwiseAbs().maxCoeff(), 1e-9);
}

TEST(Effects, PendingEffectsAreAppliedInOrderBySolve) {
  Model m = OneBody();
  m.effects = {
      Effect{EffectKind::kStiffnessScale, EffectTarget::Named("bearings"), {{"factor", 2.0}}, std::nullopt, 0},
      Effect{EffectKind::kStiffnessScale, EffectTarget::Named("bearings"), {{"factor", 0.25}}, std::nullopt, 0}};
  Model manual = OneBody();
  manual.springs[0].stiffness_factor = 0.5;
  EXPECT_NEAR(Solve(m).modes.modes[0].frequency_hz, Solve(manual).modes.modes[0].frequency_hz, 1e-9);
  EXPECT_TRUE(ApplyEffects(m).effects.empty());
}

TEST(Effects, UnknownTargetOrMissingParameterIsInputError) {
  // (An unknown kind never gets this far: the model file's reader refuses it, members_test.cpp.)
  const Model m = OneBody();
  EXPECT_THROW(
      ApplyEffect(m,
                  Effect{EffectKind::kStiffnessScale, EffectTarget::Named("nope"), {{"factor", 2.0}}, std::nullopt, 0}),
      InputError);
  EXPECT_THROW(
      ApplyEffect(m, Effect{EffectKind::kMassScale, EffectTarget::Named("nobody"), {{"factor", 2.0}}, std::nullopt, 0}),
      InputError);
  EXPECT_THROW(
      ApplyEffect(m, Effect{EffectKind::kStiffnessScale, EffectTarget::Named("bearings"), {}, std::nullopt, 0}),
      InputError);
}

TEST(Effects, CandidatesCoverEveryKindAndTargetAndStartNeutral) {
  const Model m = OneBody();
  const std::vector<Effect> c = CandidateEffects(m);
  // 2 groups x (series_compliance, stiffness_scale) + added_mass + mass_scale + ground_spring.
  EXPECT_EQ(c.size(), 7u);
  const double f0 = Solve(m).modes.modes[0].frequency_hz;
  for (const Effect& e : c) {
    const Model applied = ApplyEffect(m, e);  // every candidate applies cleanly
    if (e.kind == EffectKind::kStiffnessScale || e.kind == EffectKind::kMassScale || e.kind == EffectKind::kAddedMass) {
      EXPECT_NEAR(Solve(applied).modes.modes[0].frequency_hz, f0, 1e-9 * f0) << Describe(e);
    }
  }
}

// --- bad input -------------------------------------------------------------------------------

TEST(SolveErrors, SpringToUnknownBody) {
  Model m = OneBody();
  m.origin = "m.toml";
  m.springs[1].b.body = "frame";
  m.springs[1].line = 17;
  try {
    Solve(m);
    FAIL();
  } catch (const InputError& e) {
    const std::string s = e.what();
    EXPECT_NE(s.find("m.toml:17"), std::string::npos) << s;
    EXPECT_NE(s.find("'s2'"), std::string::npos) << s;
    EXPECT_NE(s.find("unknown body 'frame'"), std::string::npos) << s;
  }
}

TEST(SolveErrors, SingularMassMatrixNamesTheDof) {
  Model m = OneBody();
  m.bodies[0].inertia.y() = 0.0;
  try {
    Solve(m);
    FAIL();
  } catch (const InputError& e) {
    const std::string s = e.what();
    EXPECT_NE(s.find("singular mass matrix"), std::string::npos) << s;
    EXPECT_NE(s.find("c:ry"), std::string::npos) << s;
  }
}

TEST(SolveErrors, FeDofMapNotMatchingMatrix) {
  Model m;
  m.fe.origin = "dofs.csv";
  m.fe.mass = Eigen::SparseMatrix<double>(3, 3);
  m.fe.stiffness = Eigen::SparseMatrix<double>(3, 3);
  m.fe.dofs = {{1, 1}, {1, 2}};
  try {
    Solve(m);
    FAIL();
  } catch (const InputError& e) {
    const std::string s = e.what();
    EXPECT_NE(s.find("dofs.csv"), std::string::npos) << s;
    EXPECT_NE(s.find("is 3x3 but the [fe] DOF map has 2 rows"), std::string::npos) << s;
  }
}

// A DOF map naming one DOF twice: the message names the first row, in file order, that repeats an
// earlier one (rows 4 and 5 both repeat; row 4 is read first). The sorted index's lookups are what
// every FE model test resolves its springs, masses and points through.
TEST(SolveErrors, FeDofMapRowRepeatingAnEarlierRowIsNamed) {
  Model m;
  m.fe.origin = "dofs.csv";
  m.fe.mass = Eigen::SparseMatrix<double>(5, 5);
  m.fe.stiffness = Eigen::SparseMatrix<double>(5, 5);
  m.fe.dofs = {{7, 3}, {2, 1}, {5, 2}, {5, 2}, {2, 1}};
  try {
    Solve(m);
    FAIL();
  } catch (const InputError& e) {
    const std::string s = e.what();
    EXPECT_NE(s.find("dofs.csv"), std::string::npos) << s;
    EXPECT_NE(s.find("DOF map row 4: node 5 dof 2 appears twice"), std::string::npos) << s;
  }
}

}  // namespace
}  // namespace ema::model
