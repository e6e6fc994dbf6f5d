// Residuals of one model variant against every setup's test modes: per test mode, the frequency
// error in units of that mode's σ and (1 − MAC) in units of the shape σ. Pairing is redone at
// every evaluation, so mode swaps while the parameters move are followed.
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "ema/core/error.hpp"
#include "ema/correlation/correlate.hpp"
#include "ema/correlation/mac.hpp"
#include "ema/model/solve.hpp"
#include "internal.hpp"

namespace ema::diagnose::detail {

double PhaseCollinearity(const Eigen::VectorXcd& shape) {
  const double sxx = shape.real().squaredNorm(), syy = shape.imag().squaredNorm();
  const double sxy = shape.real().dot(shape.imag());
  const double total = sxx + syy;
  if (!(total > 0.0)) return 0.0;
  return ((sxx - syy) * (sxx - syy) + 4.0 * sxy * sxy) / (total * total);
}

double BlendMac(const Eigen::VectorXcd& test_shape, const Eigen::MatrixXcd& model_shapes, const Eigen::VectorXd& model_hz,
                int j, double plain_mac, double half_power_hz) {
  if (!(half_power_hz > 0.0)) return plain_mac;
  // Neighbours of j whose weight matters (within 3 half-power widths).
  std::vector<Eigen::Index> cols{j};
  double weight = 0.0;
  for (Eigen::Index k = 0; k < model_hz.size(); ++k) {
    if (k == j) continue;
    const double z = (model_hz(k) - model_hz(j)) / half_power_hz;
    if (std::abs(z) > 3.0) continue;
    cols.push_back(k);
    weight = std::max(weight, std::exp(-z * z));
  }
  if (cols.size() == 1) return plain_mac;
  Eigen::MatrixXcd basis(model_shapes.rows(), static_cast<Eigen::Index>(cols.size()));
  for (size_t c = 0; c < cols.size(); ++c) basis.col(static_cast<Eigen::Index>(c)) = model_shapes.col(cols[c]);
  const double norm = test_shape.squaredNorm();
  if (!(norm > 0.0)) return plain_mac;
  // Share of the test shape inside the span of the close model modes: bᴴ G⁺ b / φᴴφ.
  const Eigen::VectorXcd b = basis.adjoint() * test_shape;
  const Eigen::MatrixXcd gram = basis.adjoint() * basis;
  const Eigen::VectorXcd x = gram.completeOrthogonalDecomposition().solve(b);
  const double subspace = std::clamp(std::real(b.dot(x)) / norm, 0.0, 1.0);
  return plain_mac + weight * std::max(0.0, subspace - plain_mac);
}

double Huber(double s, double a) { return s <= a * a ? s : 2.0 * a * std::sqrt(s) - a * a; }

double RobustCost(const Eigen::VectorXd& r, double a) {
  double cost = 0.0;
  for (Eigen::Index i = 0; i + 1 < r.size(); i += 2) cost += Huber(r(i) * r(i) + r(i + 1) * r(i + 1), a);
  return cost;
}

Evaluator::Evaluator(const model::Model& base, std::vector<SetupData> setups, const DiagnoseOptions& options,
                     int max_modes)
    : base_(base), setups_(std::move(setups)), options_(options), max_modes_(max_modes) {
  for (const auto& s : setups_) residual_count_ += 2 * static_cast<int>(s.test_hz.size());
}

Evaluation Evaluator::Evaluate(const std::vector<model::Effect>& effects) {
  Evaluation out;
  out.r.resize(residual_count_);
  try {
    model::Model m = base_;
    for (const auto& e : effects) m = model::ApplyEffect(m, e);
    int row = 0;
    double sum_err = 0.0, sum_mac = 0.0, sum_agreement = 0.0;
    for (const SetupData& s : setups_) {
      model::SolveOptions so;
      so.setup = s.name;
      so.max_modes = max_modes_;
      const model::Solution sol = model::Solve(m, so);
      ++solves_;
      if (sol.modes.dofs.size() != s.model_dof_count)
        throw InputError(base_.origin, "the model's observed DOFs changed while fitting");
      if (sol.modes.modes.empty()) throw InputError(base_.origin, "the model has no elastic mode");
      const Eigen::MatrixXcd model_shapes = s.match.ModelShapes(sol.modes);
      Eigen::VectorXd model_hz(sol.modes.modes.size());
      for (size_t j = 0; j < sol.modes.modes.size(); ++j) model_hz(j) = sol.modes.modes[j].frequency_hz;
      const Eigen::MatrixXd mac = correlation::MacMatrix(s.test_shapes, model_shapes);
      const correlation::Pairing pairing = correlation::PairModes(mac, s.test_hz, model_hz, options_.pairing);
      std::vector<int> partner(s.test_hz.size(), -1);
      for (const correlation::ModePair& p : pairing.pairs) partner[p.test] = p.model;
      for (Eigen::Index i = 0; i < s.test_hz.size(); ++i) {
        ModeComparison c;
        c.setup = s.name;
        c.test_mode = static_cast<int>(i);
        c.test_frequency_hz = s.test_hz(i);
        const int j = partner[i];
        if (j >= 0) {
          c.model_mode = j;
          c.model_frequency_hz = model_hz(j);
          c.agreement_pct = correlation::AgreementPct(model_hz(j), s.test_hz(i));
          c.mac = mac(i, j);
          out.r(row) = (model_hz(j) - s.test_hz(i)) / s.sigma_hz(i);
          const double judged =
              BlendMac(s.test_shapes.col(i), model_shapes, model_hz, j, mac(i, j), s.half_power_hz(i));
          out.r(row + 1) = (1.0 - judged) / s.sigma_shape(i);
          sum_err += 100.0 * std::abs(model_hz(j) - s.test_hz(i)) / s.test_hz(i);
          sum_mac += mac(i, j);
          sum_agreement += c.agreement_pct;
          ++out.paired;
        } else {
          out.r(row) = options_.unpaired_frequency_residual * s.test_hz(i) / s.sigma_hz(i);
          out.r(row + 1) = 1.0 / s.sigma_shape(i);
        }
        row += 2;
        out.modes.push_back(c);
      }
    }
    if (out.paired > 0) {
      out.mean_abs_frequency_error_pct = sum_err / out.paired;
      out.mean_mac = sum_mac / out.paired;
      out.mean_agreement_pct = sum_agreement / out.paired;
    }
    out.cost = RobustCost(out.r, options_.robust_threshold);
    out.ok = true;
  } catch (const std::exception& e) {
    out.ok = false;
    out.error = e.what();
  }
  return out;
}

}  // namespace ema::diagnose::detail
