// Shapes in the likelihood (docs/diagnose.md "Shapes in the likelihood"): per measured DOF, the
// unit-norm test shape minus the model's shape fitted to it, in units of its σ there. Checked
// against hand-computed values on the benchmark's two-body stack (tests/stack_truths.hpp).
#include <gtest/gtest.h>

#include <cmath>
#include <complex>

#include "ema/correlation/mac.hpp"
#include "ema/diagnose/diagnose.hpp"
#include "ema/model/effects.hpp"
#include "ema/model/solve.hpp"
#include "stack_truths.hpp"

namespace ema::diagnose {
namespace shape_residual_test {
using model::EffectKind;
using model::Model;

double RealMac(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  const double ab = a.dot(b);
  return ab * ab / (a.squaredNorm() * b.squaredNorm());
}

// The model's own modes as the test, mode 0's shape bent at one DOF by a known real vector:
// nothing else differs, so the baseline's evidence for that mode is the bend alone.
struct BentTest {
  ModeSet modes;
  double mac = 0.0;  // of the bent shape with the model's
};

BentTest Bend(const Model& model, double amount, std::complex<double> phase) {
  BentTest t;
  t.modes = model::Solve(model, {}).modes;
  Mode& m = t.modes.modes.front();
  const Eigen::VectorXd model_shape = m.shape.real();
  Eigen::VectorXd bent = model_shape;
  bent(0) += amount * model_shape.cwiseAbs().maxCoeff();
  t.mac = RealMac(bent, model_shape);
  m.shape = bent.cast<std::complex<double>>() * phase;  // any complex scale: a real mode at another phase
  t.modes.source = "bent model modes";
  return t;
}

TEST(ShapeResidual, PerDofMisfitIsTheRootOfOneMinusMacOverTheFloor) {
  // Per DOF with a 5 % floor (no fitted σ, a real shape): σ_d = 0.05/√n of the unit-norm shape,
  // so the rms over the n DOFs of r_d is √(1 − MAC)/0.05 — whatever the shape's phase and scale.
  // (1 − MAC) gives (1 − MAC)/0.01 instead: for this 10 % bend at one DOF, 14× smaller. The
  // tolerance: the diagnosis solves the model again (round-off of ~1e-7 in the shapes).
  const Model stack = test::Stack();
  const BentTest t = Bend(stack, 0.10, std::polar(2.5, 0.7));
  ASSERT_LT(t.mac, 0.999);
  DiagnoseOptions options;
  options.max_effects = 1;
  options.members = false;
  options.shape_dof_sigma = 0.05;
  const Diagnosis per_dof = Diagnose(stack, {{"", t.modes}}, options);
  const ModeComparison& bent = per_dof.baseline.modes.front();
  EXPECT_NEAR(bent.shape_misfit_sigma, std::sqrt(1.0 - t.mac) / 0.05, 1e-4 * std::sqrt(1.0 - t.mac) / 0.05);
  // Every other mode is the model's own: no shape misfit.
  for (size_t i = 1; i < per_dof.baseline.modes.size(); ++i)
    EXPECT_LT(per_dof.baseline.modes[i].shape_misfit_sigma, 1e-4) << "mode " << i;
  // One residual per measured DOF and a frequency row per mode.
  const int dofs = static_cast<int>(t.modes.dofs.size()), modes = static_cast<int>(t.modes.modes.size());
  EXPECT_EQ(per_dof.residual_count, modes * (1 + dofs));
  EXPECT_EQ(per_dof.test_mode_count, modes);

  options.shape_residual = ShapeResidual::kOneMinusMac;
  const Diagnosis mac = Diagnose(stack, {{"", t.modes}}, options);
  EXPECT_NEAR(mac.baseline.modes.front().shape_misfit_sigma, (1.0 - t.mac) / 0.01, 1e-4 * (1.0 - t.mac) / 0.01);
  EXPECT_EQ(mac.residual_count, 2 * modes);
}

TEST(ShapeResidual, TheFittedSigmaOfAShapeWidensItsResidual) {
  // The fit's own σ of |φ| per DOF (ema fit --json `std`) enters σ_d beside the floor: four times
  // the floor at every DOF leaves √(1 + 16) ≈ 4.1 times less misfit.
  const Model stack = test::Stack();
  BentTest t = Bend(stack, 0.10, 1.0);
  Mode& m = t.modes.modes.front();
  const double norm = m.shape.norm();
  const double n = static_cast<double>(m.shape.size());
  m.shape_std = Eigen::VectorXd::Constant(m.shape.size(), 4.0 * 0.05 / std::sqrt(n) * norm);
  DiagnoseOptions options;
  options.max_effects = 1;
  options.members = false;
  options.shape_dof_sigma = 0.05;
  const Diagnosis d = Diagnose(stack, {{"", t.modes}}, options);
  EXPECT_NEAR(d.baseline.modes.front().shape_misfit_sigma, std::sqrt(1.0 - t.mac) / 0.05 / std::sqrt(17.0),
              1e-4 * std::sqrt(1.0 - t.mac) / 0.05);
}

TEST(ShapeResidual, BadShapeOptionsAreRefused) {
  DiagnoseOptions options;
  options.shape_dof_sigma = 0.0;
  std::string why;
  EXPECT_FALSE(options.IsValid(&why));
  EXPECT_NE(why.find("shape_dof_sigma"), std::string::npos) << why;
  ShapeResidual r = ShapeResidual::kPerDof;
  EXPECT_TRUE(StringToShapeResidual("mac", &r));
  EXPECT_EQ(r, ShapeResidual::kOneMinusMac);
  EXPECT_EQ(ShapeResidualToString(ShapeResidual::kPerDof), "per-dof");
  EXPECT_FALSE(StringToShapeResidual("per_dof", &r));
}

}  // namespace shape_residual_test
}  // namespace ema::diagnose
