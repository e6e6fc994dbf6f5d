#include "ema/curvefit/lsfd.hpp"

#include <Eigen/Cholesky>
#include <Eigen/QR>
#include <Eigen/SVD>
#include <cmath>
#include <sstream>

#include "ema/core/error.hpp"
#include "ema/curvefit/complexity.hpp"

namespace ema::curvefit {

using cd = std::complex<double>;

LsfdResult EstimateModeShapes(const FitData& data, const std::vector<SelectedPole>& poles, const LsfdOptions& options,
                              const SetPoles* set_poles, const ProgressCallback& progress) {
  const int n = data.LineCount(), l = data.OutputCount(), m = data.ReferenceCount();
  const int nm = static_cast<int>(poles.size());
  const int n_res = (options.lower_residual ? m : 0) + (options.upper_residual ? m : 0);
  const int n_unk = 2 * nm + n_res;
  const int used = data.UsedLineCount();
  if (2 * used * m < n_unk + 1)
    throw InputError("lsfd", "too few valid lines (" + std::to_string(used) + ") for " + std::to_string(nm) + " modes");
  const int k_pow = data.frf_type == FrfType::kReceptance ? 0 : data.frf_type == FrfType::kMobility ? 1 : 2;

  // Groups of outputs fitted with one set of poles: every output at once, or each roving set
  // with its own (set_poles).
  std::vector<std::vector<int>> groups;
  std::vector<std::vector<cd>> group_poles;
  if (set_poles) {
    groups = set_poles->outputs;
    group_poles = set_poles->lambda_fitted;
  } else {
    groups.emplace_back();
    for (int o = 0; o < l; ++o) groups.back().push_back(o);
    group_poles.emplace_back();
    for (const auto& p : poles) group_poles.back().push_back(p.pole.lambda_fitted);
  }
  Eigen::MatrixXd X(n_unk, l);
  double err2 = 0.0, ref2 = 0.0;
  // Three steps per group (design, solve, residual): the share done, to `progress`.
  const auto step = [&](size_t g, int part) {
    ReportProgress(progress, (static_cast<double>(g) + part / 3.0) / static_cast<double>(groups.size()), "mode shapes");
  };
  for (size_t g = 0; g < groups.size(); ++g) {
  step(g, 0);
  const std::vector<int>& outs = groups[g];
  // Design matrix, rows (line, reference, re/im); identical for every output of the group (no
  // per-output weights), so one QR serves them all.
  const int rows = 2 * n * m;
  Eigen::MatrixXd P = Eigen::MatrixXd::Zero(rows, n_unk);
  for (int f = 0; f < n; ++f) {
    if (data.line_weight[f] == 0.0) continue;
    const cd jw(0.0, kTwoPi * data.frequency_hz[f]);
    const cd factor = std::pow(jw, k_pow);
    for (int i = 0; i < m; ++i) {
      const int row = 2 * (f * m + i);
      auto put = [&](int col, cd v) {
        P(row, col) = v.real();
        P(row + 1, col) = v.imag();
      };
      for (int r = 0; r < nm; ++r) {
        const cd lam = group_poles[g][static_cast<size_t>(r)];
        const cd li = poles[r].pole.participation.size() == m ? poles[r].pole.participation[i] : cd(1.0);
        const cd g1 = li / (jw - lam), g2 = std::conj(li) / (jw - std::conj(lam));
        put(2 * r, factor * (g1 + g2));                 // Re phi
        put(2 * r + 1, factor * cd(0, 1) * (g1 - g2));  // Im phi
      }
      int col = 2 * nm;
      if (options.lower_residual) put(col + i, factor / (jw * jw)), col += m;
      if (options.upper_residual) put(col + i, factor);
    }
  }
  // Column scaling: modal, lower and upper regressors differ by orders of magnitude.
  Eigen::VectorXd scale = P.colwise().norm().transpose();
  for (int c = 0; c < n_unk; ++c) scale[c] = scale[c] > 0.0 ? 1.0 / scale[c] : 0.0;
  P = P * scale.asDiagonal();
  const int lg = static_cast<int>(outs.size());
  Eigen::MatrixXd B(rows, lg);
  for (int k = 0; k < lg; ++k)
    for (int f = 0; f < n; ++f)
      for (int i = 0; i < m; ++i) {
        const cd h = data.line_weight[f] == 0.0 ? cd(0.0) : data.H(f, outs[static_cast<size_t>(k)], i);
        B(2 * (f * m + i), k) = h.real();
        B(2 * (f * m + i) + 1, k) = h.imag();
      }
  step(g, 1);
  // Normal equations of the column-scaled design (unit-norm columns keep cond(P^T P) modest);
  // QR when the Cholesky factor shows rank trouble.
  Eigen::MatrixXd gram = Eigen::MatrixXd::Zero(n_unk, n_unk);
  gram.selfadjointView<Eigen::Lower>().rankUpdate(P.transpose());
  Eigen::LLT<Eigen::MatrixXd> llt(gram.selfadjointView<Eigen::Lower>());
  const Eigen::VectorXd diag = llt.matrixL().toDenseMatrix().diagonal();
  Eigen::MatrixXd Xg;
  if (llt.info() == Eigen::Success && diag.minCoeff() > 1e-6 * diag.maxCoeff()) {
    Xg = llt.solve(P.transpose() * B);
  } else {
    Xg = Eigen::HouseholderQR<Eigen::MatrixXd>(P).solve(B);
  }
  step(g, 2);
  err2 += (P * Xg - B).squaredNorm();
  ref2 += B.squaredNorm();
  Xg = scale.asDiagonal() * Xg;
  for (int k = 0; k < lg; ++k) X.col(outs[static_cast<size_t>(k)]) = Xg.col(k);
  }
  const double err = std::sqrt(err2), ref = std::sqrt(ref2);
  ReportProgress(progress, 1.0, "mode shapes");

  LsfdResult result;
  result.synthesis_error = ref > 0.0 ? err / ref : 0.0;
  result.residues.resize(l * m, nm);
  result.lower_residual = Eigen::VectorXd::Zero(l * m);
  result.upper_residual = Eigen::VectorXd::Zero(l * m);
  for (int o = 0; o < l; ++o)
    for (int i = 0; i < m; ++i) {
      int col = 2 * nm;
      if (options.lower_residual) result.lower_residual[o * m + i] = X(col + i, o), col += m;
      if (options.upper_residual) result.upper_residual[o * m + i] = X(col + i, o);
    }
  ModeSet& set = result.modes;
  set.dofs = data.outputs;
  // Driving points: an output on the node and axis of a reference. A reference named the other way
  // round (hammer at 101-Z, sensor at 101+Z) is a driving point too, its FRF negated: `sign`.
  struct Driving {
    int o, i;
    double sign;
  };
  std::vector<Driving> driving;
  for (int i = 0; i < m; ++i)
    for (int o = 0; o < l; ++o) {
      const Dof& out = data.outputs[o];
      const Dof& ref = data.references[i];
      if (out.node == ref.node && out.direction != 0 && std::abs(out.direction) == std::abs(ref.direction))
        driving.push_back({o, i, (out.direction > 0) == (ref.direction > 0) ? 1.0 : -1.0});
    }

  for (int r = 0; r < nm; ++r) {
    const Pole& pole = poles[r].pole;
    Eigen::VectorXcd phi(l);
    for (int o = 0; o < l; ++o) phi[o] = cd(X(2 * r, o), X(2 * r + 1, o));
    Eigen::VectorXcd lr = pole.participation.size() == m ? pole.participation : Eigen::VectorXcd::Ones(m);
    for (int o = 0; o < l; ++o)
      for (int i = 0; i < m; ++i) result.residues(o * m + i, r) = phi[o] * lr[i];

    Mode mode;
    mode.pole = pole.lambda;
    PoleToFrequencyAndDamping(pole.lambda, &mode.frequency_hz, &mode.damping_ratio);
    mode.participation = lr;
    mode.frequency_spread_hz = poles[r].frequency_spread_hz;
    mode.damping_spread = poles[r].damping_spread;
    Eigen::VectorXcd shape;
    if (!driving.empty()) {
      // c^2 = l_i / phi_{d_i}, weighted by |l_i phi_{d_i}| over the driving points (§4.2); then
      // psi_hat = c phi is modal-A scaled and sqrt(2 j w_d) psi_hat has unit modal mass.
      cd c2 = 0.0;
      double wsum = 0.0;
      for (auto [o, i, sign] : driving) {
        if (std::abs(phi[o]) == 0.0) continue;
        const double w = std::abs(lr[i] * phi[o]);
        c2 += w * sign * lr[i] / phi[o];
        wsum += w;
      }
      // A driving-point receptance residue is phi_d^2/(2j w_d m) with m > 0: negative imaginary.
      // The opposite sign means an inverted sensor or hammer direction in the data; the shape
      // then comes out rotated by 90 degrees. Only driving points where the mode really shows
      // (residue >= 10 % of the largest driving-point residue) count: at a node of the mode the
      // residue is noise and its sign means nothing.
      double largest_driving = 0.0;
      for (auto [o, i, sign] : driving) largest_driving = std::max(largest_driving, std::abs(phi[o] * lr[i]));
      for (auto [o, i, sign] : driving)
        if ((sign * phi[o] * lr[i]).imag() > 0.0 && std::abs(phi[o] * lr[i]) >= 0.1 * largest_driving) {
          std::ostringstream msg;
          msg << "mode at " << pole.frequency_hz << " Hz: driving point " << DofName(data.outputs[o])
              << " has a residue of the sign of a negative modal mass (inverted sensor or hammer sign?);"
                 " unit-modal-mass shape is rotated by 90 degrees";
          result.warnings.push_back(msg.str());
          break;
        }
      if (wsum > 0.0) {
        const cd c = std::sqrt(c2 / wsum);
        shape = phi * c * std::sqrt(cd(0.0, 2.0 * pole.lambda.imag()));
        mode.unit_modal_mass = true;
      }
    }
    if (shape.size() == 0) {
      // No driving point: the residue column of the strongest reference, unit largest entry.
      int imax = 0;
      lr.cwiseAbs().maxCoeff(&imax);
      shape = phi * lr[imax];
      int omax = 0;
      shape.cwiseAbs().maxCoeff(&omax);
      if (std::abs(shape[omax]) > 0.0) shape /= shape[omax];
    } else {
      // The sign of a square root is arbitrary: make the largest entry's real part positive.
      int omax = 0;
      shape.cwiseAbs().maxCoeff(&omax);
      if (shape[omax].real() < 0.0) shape = -shape;
    }
    mode.shape = shape;
    mode.mpc = ModalPhaseCollinearity(shape);
    mode.mpd = MeanPhaseDeviationDeg(shape);
    mode.mcf = ModeComplexityFactor(shape);
    set.modes.push_back(std::move(mode));
  }
  return result;
}

}  // namespace ema::curvefit
