// FRF-domain generator from known truth (algorithms.md §7.2): real unit-modal-mass shapes,
// modal damping, exact pole-residue FRFs plus complex Gaussian noise with a fixed seed.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <complex>
#include <random>
#include <vector>

#include "ema/core/types.hpp"

namespace ema::curvefit::test {

struct TruthMode {
  double f_hz;
  double zeta;
  Eigen::VectorXd shape;  ///< unit modal mass, one entry per DOF of the structure
};

struct Truth {
  std::vector<TruthMode> modes;
  int n_dofs = 0;
};

/// Smooth beam-like shapes sin((r+1) pi (x+0.3)/n) at n DOFs, scaled by `mass_scale`.
inline Truth MakeTruth(const std::vector<double>& f_hz, const std::vector<double>& zeta, int n_dofs, double mass_scale = 0.5) {
  Truth t;
  t.n_dofs = n_dofs;
  for (size_t r = 0; r < f_hz.size(); ++r) {
    TruthMode mode{f_hz[r], zeta[r], Eigen::VectorXd(n_dofs)};
    for (int d = 0; d < n_dofs; ++d)
      mode.shape[d] = mass_scale * std::sin((r + 1) * M_PI * (d + 0.7) / (n_dofs + 0.4));
    t.modes.push_back(mode);
  }
  return t;
}

/// Accelerance (k = 2), mobility (1) or receptance (0) FRFs from every DOF in `refs` to every DOF,
/// lines 0..f_max (line 0 at DC is NaN-free but excluded by the fitter), complex noise of
/// `noise` × RMS of each FRF. `decay_rate` shifts every pole left (exponential window).
inline FrfSet MakeFrfSet(const Truth& truth, const std::vector<int>& refs, double f_max, double df, double noise,
                         unsigned seed, int k_pow = 2, double decay_rate = 0.0) {
  FrfSet set;
  const int n = static_cast<int>(std::lround(f_max / df)) + 1;
  set.frequency_hz = Eigen::VectorXd::LinSpaced(n, 0.0, (n - 1) * df);
  for (int d = 0; d < truth.n_dofs; ++d) set.outputs.push_back({d + 1, 3});
  for (int r : refs) set.references.push_back({r + 1, 3});
  set.output_quantity = k_pow == 2 ? Quantity::kAcceleration : k_pow == 1 ? Quantity::kVelocity : Quantity::kDisplacement;
  set.window_decay_rate = decay_rate;
  std::mt19937 rng(seed);
  std::normal_distribution<double> gauss(0.0, 1.0);
  for (int ref : refs) {
    Eigen::MatrixXcd h(n, truth.n_dofs);
    for (int k = 0; k < n; ++k) {
      const std::complex<double> jw(0.0, kTwoPi * set.frequency_hz[k]);
      for (int d = 0; d < truth.n_dofs; ++d) {
        std::complex<double> v = 0.0;
        for (const auto& mode : truth.modes) {
          const std::complex<double> lam = FrequencyAndDampingToPole(mode.f_hz, mode.zeta) - decay_rate;
          const std::complex<double> res = mode.shape[d] * mode.shape[ref] / std::complex<double>(0.0, 2.0 * lam.imag());
          v += res / (jw - lam) + std::conj(res) / (jw - std::conj(lam));
        }
        h(k, d) = v * std::pow(jw, k_pow);
      }
    }
    for (int d = 0; d < truth.n_dofs; ++d) {
      const double rms = std::sqrt(h.col(d).squaredNorm() / n);
      for (int k = 0; k < n; ++k)
        h(k, d) += noise * rms * std::complex<double>(gauss(rng), gauss(rng)) / std::sqrt(2.0);
    }
    set.h.push_back(h);
  }
  return set;
}

/// Roving-set inconsistency: modes at 30, 50 and 80 Hz (ζ 1 %, 12 outputs, references 2 and 9)
/// with the 50 Hz mode measured at `shifted_hz` on outputs 7-12 (the second roving set, whose
/// sensors load the structure differently); 1 % noise, fixed seeds.
inline FrfSet TwoRovingSetsWithShiftedMode(double shifted_hz) {
  const Truth a = MakeTruth({30.0, 50.0, 80.0}, {0.01, 0.01, 0.01}, 12);
  Truth b = a;
  b.modes[1].f_hz = shifted_hz;
  const FrfSet set_a = MakeFrfSet(a, {1, 8}, 120.0, 0.05, 0.01, 31);
  const FrfSet set_b = MakeFrfSet(b, {1, 8}, 120.0, 0.05, 0.01, 32);
  FrfSet frfs = set_a;
  for (size_t r = 0; r < frfs.h.size(); ++r) frfs.h[r].rightCols(6) = set_b.h[r].rightCols(6);
  return frfs;
}

}  // namespace ema::curvefit::test
