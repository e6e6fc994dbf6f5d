// Time integration of hammer impacts on structures with non-linear elements (time_simulator.hpp).
#include "ema/acquisition/time_simulator.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "antialias.hpp"
#include "ema/core/error.hpp"

namespace ema::acquisition {

TimeIntegrator::TimeIntegrator(TimeDomainTruth truth) : truth_(std::move(truth)) {
  const Eigen::Index n = truth_.mass.rows();
  if (n == 0 || truth_.mass.cols() != n || truth_.stiffness.rows() != n || truth_.stiffness.cols() != n ||
      truth_.observation.cols() != n || truth_.observation.rows() != static_cast<Eigen::Index>(truth_.dofs.size()))
    throw std::invalid_argument("TimeIntegrator: inconsistent matrix sizes");
  for (const NonlinearElement& e : truth_.elements)
    if (e.coefficients.size() != n || !e.force) throw std::invalid_argument("TimeIntegrator: bad non-linear element");
  Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> es(truth_.stiffness, truth_.mass,
                                                               Eigen::ComputeEigenvectors | Eigen::Ax_lBx);
  if (es.info() != Eigen::Success) throw std::invalid_argument("TimeIntegrator: eigen-solution failed (M not positive definite?)");
  phi_ = es.eigenvectors();
  const Eigen::VectorXd lambda = es.eigenvalues();
  const double limit = 1e-12 * std::max(1.0, lambda.cwiseAbs().maxCoeff()) + std::pow(kTwoPi * 1e-3, 2);
  omega_.resize(n);
  zeta_.resize(n);
  int elastic = 0;
  for (Eigen::Index r = 0; r < n; ++r) {
    const bool rigid = lambda[r] <= limit;
    omega_[r] = rigid ? 0.0 : std::sqrt(lambda[r]);
    if (rigid || truth_.damping_ratios.empty()) {
      zeta_[r] = 0.0;
    } else {
      const auto i = std::min<std::size_t>(static_cast<std::size_t>(elastic), truth_.damping_ratios.size() - 1);
      zeta_[r] = truth_.damping_ratios[i];
      ++elastic;
    }
    frequency_hz_.push_back(omega_[r] / kTwoPi);
  }
  element_modal_.resize(static_cast<Eigen::Index>(truth_.elements.size()), n);
  for (std::size_t e = 0; e < truth_.elements.size(); ++e)
    element_modal_.row(static_cast<Eigen::Index>(e)) = truth_.elements[e].coefficients.transpose() * phi_;
  output_modal_ = truth_.observation * phi_;
}

int TimeIntegrator::IndexOf(const Dof& dof) const {
  for (std::size_t i = 0; i < truth_.dofs.size(); ++i)
    if (truth_.dofs[i] == dof) return static_cast<int>(i);
  throw std::invalid_argument("TimeIntegrator: DOF " + DofName(dof) + " is not among the truth's DOFs");
}

ImpactSignals TimeIntegrator::Simulate(const Dof& ref, const std::vector<Dof>& responses,
                                       const std::vector<std::pair<double, double>>& pulses, double pulse_duration_s,
                                       double sample_rate_hz, int samples, Quantity quantity, int requested_oversampling) {
  if (sample_rate_hz <= 0.0 || samples <= 0 || pulse_duration_s <= 0.0 || requested_oversampling < 1)
    throw std::invalid_argument("TimeIntegrator: sample rate, samples, pulse duration and oversampling must be > 0");
  // A pulse shorter than a few fine steps would be sampled at zero or one point: refine the grid.
  const int oversampling = EffectiveOversampling(pulse_duration_s, sample_rate_hz, requested_oversampling);
  const std::vector<double> fir = internal::DesignAntiAlias(oversampling);
  const int half = static_cast<int>(fir.size() / 2);
  const int n_fine = (samples - 1) * oversampling + 2 * half + 1;
  const double dt = 1.0 / (sample_rate_hz * oversampling);
  const double omega_c = internal::kPi / pulse_duration_s;

  std::vector<double> u(n_fine, 0.0);
  for (const auto& [t0, peak] : pulses)
    for (int i = 0; i < n_fine; ++i) {
      const double tau = (i - half) * dt - t0;
      if (tau >= 0.0 && tau <= pulse_duration_s) u[i] += peak * std::sin(omega_c * tau);
    }

  const Eigen::Index n = phi_.cols();
  const int ne = static_cast<int>(truth_.elements.size());
  // Generalised force per unit hammer force: the hammer DOF's observation row, in modes.
  const Eigen::VectorXd b = output_modal_.row(IndexOf(ref)).transpose();
  std::vector<int> rows;
  for (const Dof& d : responses) rows.push_back(IndexOf(d));
  Eigen::MatrixXd out_modal(static_cast<Eigen::Index>(rows.size()), n);
  for (std::size_t o = 0; o < rows.size(); ++o) out_modal.row(static_cast<Eigen::Index>(o)) = output_modal_.row(rows[o]);

  // Newmark, average acceleration (beta = 1/4, gamma = 1/2), per mode.
  const double a0 = 4.0 / (dt * dt), a1 = 2.0 / dt, a2 = 4.0 / dt;
  const Eigen::VectorXd c2 = 2.0 * zeta_.cwiseProduct(omega_);          // 2 ζ ω
  const Eigen::VectorXd k_eff = omega_.cwiseAbs2() + a1 * c2 + Eigen::VectorXd::Constant(n, a0);
  const Eigen::VectorXd inv_k = k_eff.cwiseInverse();
  // Element compressions c = E q; their forces act on the modes through E^T.
  const Eigen::MatrixXd& e_modal = element_modal_;
  const Eigen::MatrixXd g = ne > 0 ? Eigen::MatrixXd(e_modal * inv_k.asDiagonal() * e_modal.transpose())
                                   : Eigen::MatrixXd(0, 0);
  std::vector<double> k_lin(ne);
  for (int e = 0; e < ne; ++e) {
    truth_.elements[e].force->Reset();
    k_lin[e] = truth_.elements[e].force->Stiffness();
  }
  auto rho = [&](const Eigen::VectorXd& c) {
    Eigen::VectorXd r(ne);
    for (int e = 0; e < ne; ++e) r[e] = truth_.elements[e].force->Force(c[e]) - k_lin[e] * c[e];
    return r;
  };

  Eigen::VectorXd q = Eigen::VectorXd::Zero(n), v = q, a = q;
  a = b * u[0];  // at rest, unit modal masses
  Eigen::VectorXd c = Eigen::VectorXd::Zero(ne), r = Eigen::VectorXd::Zero(ne);
  double c_scale = 1e-12;
  const int order = quantity == Quantity::kDisplacement ? 0 : quantity == Quantity::kVelocity ? 1 : 2;
  std::vector<std::vector<double>> fine(rows.size(), std::vector<double>(n_fine, 0.0));
  auto record = [&](int i) {
    const Eigen::VectorXd& s = order == 0 ? q : order == 1 ? v : a;
    const Eigen::VectorXd y = out_modal * s;
    for (std::size_t o = 0; o < rows.size(); ++o) fine[o][i] = y[static_cast<Eigen::Index>(o)];
  };
  record(0);
  for (int i = 1; i < n_fine; ++i) {
    const Eigen::VectorXd rhs = b * u[i] + (a0 * q + a2 * v + a) + c2.cwiseProduct(a1 * q + v);
    Eigen::VectorXd q_new = rhs.cwiseProduct(inv_k);
    if (ne > 0) {
      const Eigen::VectorXd c_lin = e_modal * q_new;
      // c = c_lin - G rho(c), by fixed-point iteration from the last step's forces.
      Eigen::VectorXd c_it = c_lin - g * r;
      bool converged = false;
      for (int it = 0; it < 200; ++it) {
        const Eigen::VectorXd r_it = rho(c_it);
        const Eigen::VectorXd c_next = c_lin - g * r_it;
        const double change = (c_next - c_it).cwiseAbs().maxCoeff();
        // Relative to the largest compression met so far in this impact (1 pm at least), so
        // that round-off about the operating point at rest does not stall the test.
        c_scale = std::max(c_scale, c_next.cwiseAbs().maxCoeff());
        const double scale = c_scale;
        c_it = c_next;
        r = r_it;
        if (change <= 1e-12 * scale) {
          converged = true;
          break;
        }
      }
      if (!converged)
        throw ConvergenceError("time integration: the non-linear element forces do not converge within a step of " +
                                 std::to_string(dt) + " s; raise the oversampling");
      r = rho(c_it);
      c = c_it;
      q_new -= inv_k.cwiseProduct(e_modal.transpose() * r);
      for (int e = 0; e < ne; ++e) truth_.elements[e].force->Commit(c[e]);
    }
    const Eigen::VectorXd a_new = a0 * (q_new - q) - a2 * v - a;
    v += 0.5 * dt * (a + a_new);
    a = a_new;
    q = q_new;
    record(i);
  }

  ImpactSignals out;
  out.force = internal::FilterDecimate(u, fir, oversampling, samples);
  for (std::size_t o = 0; o < rows.size(); ++o)
    out.responses.push_back(internal::FilterDecimate(fine[o], fir, oversampling, samples));
  return out;
}

}  // namespace ema::acquisition
