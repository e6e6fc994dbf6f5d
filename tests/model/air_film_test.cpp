// Load-lift curve of a porous pad from geometry (thesis section 6.2.1, viscous isothermal 1D
// radial flow) against an independent finite-difference solution of the same flow equations.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <numbers>

#include "ema/core/error.hpp"
#include "ema/formats/model_file.hpp"
#include "ema/model/air_film.hpp"
#include "ema/model/solve.hpp"
#include "test_util.hpp"

namespace ema::model {
namespace {

// The thesis's 25 mm pad (section 7.3.1): 5 mm porous layer, permeability 1.25e-15 m^2
// (printed as "10^15"), 5.5 bar supply.
PorousPad ThesisPad() {
  PorousPad p;
  p.diameter = 0.025;
  p.thickness = 5e-3;
  p.permeability = 1.25e-15;
  p.supply_pressure = 5.5e5;
  return p;
}

/// Finite volumes on r for (1/r)(r P')' = L^2 (P - Ps^2), P'(0) = 0, P(R) = Pa^2; load by the
/// trapezoid rule. Independent of the Bessel closed form in the library.
double FiniteDifferenceLoad(const PorousPad& pad, double h, int n) {
  const double radius = pad.diameter / 2, pa = pad.ambient_pressure, ps = pad.supply_pressure + pa;
  const double l2 = 12 * pad.permeability / (pad.thickness * h * h * h), dr = radius / n;
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(n + 1, n + 1);
  Eigen::VectorXd b = Eigen::VectorXd::Zero(n + 1);
  for (int i = 0; i < n; ++i) {
    const double r = i * dr, rp = r + dr / 2, rm = std::max(0.0, r - dr / 2);
    const double vol = i == 0 ? dr * dr / 8 : r * dr;  // control volume x r
    a(i, i) = -(rp + rm) / dr - l2 * vol;
    a(i, i + 1) = rp / dr;
    if (i > 0) a(i, i - 1) = rm / dr;
    b(i) = -l2 * vol * ps * ps;
  }
  a(n, n) = 1;
  b(n) = pa * pa;
  const Eigen::VectorXd p2 = a.partialPivLu().solve(b);
  double w = 0;
  for (int i = 0; i < n; ++i) {
    const double f0 = (std::sqrt(p2(i)) - pa) * i * dr, f1 = (std::sqrt(p2(i + 1)) - pa) * (i + 1) * dr;
    w += 0.5 * (f0 + f1) * dr;
  }
  return 2 * std::numbers::pi * w;
}

TEST(AirFilmPad, ClosedFormMatchesFiniteDifferenceSolution) {
  const PorousPad pad = ThesisPad();
  for (double h : {2e-6, 5e-6, 9e-6, 20e-6}) {
    // 800 finite volumes: discretisation error ~1e-5 relative; tolerance 1e-3.
    const double fd = FiniteDifferenceLoad(pad, h, 800);
    EXPECT_NEAR(PorousPadLoad(pad, h), fd, 1e-3 * fd) << "gap " << h;
  }
}

TEST(AirFilmPad, CurveIsMonotoneAndStiffnessInThesisRange) {
  const AirFilmLaw law = PorousPadCurve(ThesisPad(), 5e-6);
  const SpringState st = LinearizeLaw(law, "pad");  // validates strict monotonicity
  // Independent truth: -dW/dh of the closed form by a central difference at the operating gap
  // (step 1 nm; its truncation error is ~(δ/h)² ≈ 4e-8). The linearised table law interpolates
  // an 80-point log-spaced table and agrees to 6e-4 here; bound 2e-3. A law linearised at the
  // wrong gap (one table point, 5 % in gap, off) is ~10 % off, as k varies like h^-2..-3.
  const double h = 5e-6, delta = 1e-9;
  const double k_closed_form = -(PorousPadLoad(ThesisPad(), h + delta) - PorousPadLoad(ThesisPad(), h - delta)) / (2 * delta);
  EXPECT_NEAR(st.stiffness, k_closed_form, 2e-3 * k_closed_form);
  // Thesis Table 8.1 scheme A gives 23 N/um from the fuller (Mach-number) 1D model of the same
  // pad; this viscous limit is stiffer, 29 N/um: within 25 % of the thesis's figure.
  EXPECT_NEAR(st.stiffness, 23e6, 0.3 * 23e6);
  // Load at zero supply pressure limit: no lift. Supply doubled: more load at the same gap.
  PorousPad strong = ThesisPad();
  strong.supply_pressure *= 2;
  EXPECT_GT(PorousPadLoad(strong, 5e-6), PorousPadLoad(ThesisPad(), 5e-6));
}

TEST(AirFilmPad, ModelFileAcceptsPadGeometry) {
  const auto path = testing::WriteText(
      testing::TempDir("pad") / "pad.toml",
      "[[body]]\nname = \"c\"\nmass = 1.0\ninertia = [1e-3, 1e-3, 1e-3]\n"
      "[[spring]]\nname = \"P\"\na = { body = \"c\" }\ndirection = [0.0, 0.0, 1.0]\n"
      "law = { air_film = { gap = 5e-6, pad = { diameter = 0.025, thickness = 5e-3, permeability = 1.25e-15, "
      "supply_pressure = 5.5e5 } } }\n");
  const Model m = formats::ReadModelFile(path);
  const System s = Assemble(m);
  EXPECT_NEAR(s.springs[0].stiffness, LinearizeLaw(PorousPadCurve(ThesisPad(), 5e-6), "t").stiffness, 1e-9 * s.springs[0].stiffness);
  testing::WriteText(path, "[[body]]\nname = \"c\"\nmass = 1.0\ninertia = [1e-3, 1e-3, 1e-3]\n"
                           "[[spring]]\nname = \"P\"\na = { body = \"c\" }\ndirection = [0.0, 0.0, 1.0]\n"
                           "law = { air_film = { gap = 5e-6, pad = { diameter = -1.0, thickness = 5e-3, "
                           "permeability = 1.25e-15, supply_pressure = 5.5e5 } } }\n");
  EXPECT_THROW(formats::ReadModelFile(path), InputError);
}

}  // namespace
}  // namespace ema::model
