// Maximum-likelihood modal-model refinement by variable projection (see ml_refine.hpp).
//
// Notation (per Levenberg-Marquardt evaluation):
//   A  n × p  complex basis of the linear unknowns of one FRF, per mode r the two columns
//             a_r = F (g + g~), b_r = F j (g - g~) with g = 1/(jw - lambda), g~ = 1/(jw - conj lambda),
//             F = (jw)^k, so that x_a a_r + x_b b_r = F (R g + conj(R) g~) with R = x_a + j x_b;
//             then F/(jw)^2 (lower residual) and F (upper residual). Columns scaled to unit norm.
//   B  n × 2N complex derivative basis, per mode beta1 = F (q + q~), beta2 = F j (q - q~), q = g^2:
//             d model/d Re(lambda) = x_a beta1 + x_b beta2,  d model/d Im(lambda) = x_a beta2 - x_b beta1.
//   Real inner products <u, v> = Re(u^H v), weights w = 2/sigma^2 so every real residual has unit
//   variance and the Gauss-Newton matrix is the Fisher information.
// With C = [A B] and per segment s: G_s = <C_s, C_s> and V_s = <C_s, H_s> (one real GEMM for all
// FRFs). Per FRF c with segment weights w_cs: Gw = sum_s w_cs G_s, vw = sum_s w_cs V_s(:, c).
//   x = Gw_AA^-1 vw_A, cost = sum w |h|^2 - x . vw_A,
//   Kaufman: J^T J = M^T Gw_BB M - (Gw_AB M)^T Gw_AA^-1 (Gw_AB M),  J^T r = -M^T (vw_B - Gw_BA x)
// where M (2N × 2N) maps B's columns to the pole derivatives (block-diagonal from x).
#include "ema/curvefit/ml_refine.hpp"

#include <ceres/ceres.h>

#include "ema/core/solver_logging.hpp"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <sstream>
#include <thread>

#include "ema/core/error.hpp"
#include "ema/core/parallel.hpp"
#include "ema/curvefit/polymax.hpp"

namespace ema::curvefit {

namespace {

using cd = std::complex<double>;

// The refinement's progress, and where a progress callback that throws (a cancellation) stops it.
// Every report comes from the calling thread (Ceres runs on it: num_threads = 1): after each
// iteration the share of the iteration limit, and between the expensive parts of each evaluation
// the last share again. What the callback throws is kept: the evaluation then fails and the
// iteration callback aborts the solve, so that no exception crosses Ceres' own frames, and it is
// rethrown once Ceres has returned (RethrowIfThrown).
class RefineProgress {
 public:
  explicit RefineProgress(const ProgressCallback& progress) : progress_(progress) {}
  /// Reports `fraction` (< 0: the last one again); true once the callback has thrown.
  bool Report(double fraction = -1.0) {
    if (thrown_) return true;
    if (!progress_) return false;
    if (fraction >= 0.0) fraction_ = fraction;
    try {
      progress_(fraction_, "ML refinement");
    } catch (...) {
      thrown_ = std::current_exception();
    }
    return static_cast<bool>(thrown_);
  }
  void RethrowIfThrown() const {
    if (thrown_) std::rethrow_exception(thrown_);
  }

 private:
  const ProgressCallback& progress_;
  double fraction_ = 0.0;
  std::exception_ptr thrown_;
};

// Everything that does not change between evaluations.
struct Problem {
  int n = 0;           // used lines
  int n_frf = 0;
  int n_modes = 0;
  int p = 0;           // linear unknowns per FRF
  bool lower = true, upper = true;
  int k_pow = 2;
  Eigen::VectorXd omega;                // rad/s, used lines
  std::vector<int> seg_start;           // S+1 boundaries in used-line index
  std::vector<Eigen::MatrixXd> h_real;  // per segment: [Re H; Im H] (2 n_s × n_frf)
  Eigen::MatrixXd hh;                   // S × n_frf: sum |h|^2 per segment
  Eigen::MatrixXd w;                    // S × n_frf: weights 2/sigma^2
  int threads = 1;
  RefineProgress* progress = nullptr;   // asked between the parts of an evaluation

  int Segments() const { return static_cast<int>(seg_start.size()) - 1; }
};

struct Evaluation {
  bool ok = false;
  double cost = 0.0;           // sum of squared normalised residuals (= 2 × Ceres cost)
  Eigen::MatrixXd jtj;         // 2N × 2N
  Eigen::VectorXd jtr;         // 2N
  Eigen::MatrixXd x;           // p × n_frf unscaled linear unknowns
  Eigen::MatrixXd x_std;       // p × n_frf 1 sigma of x (poles fixed, unit noise scale)
  Eigen::VectorXd frf_sse;     // unweighted sum |e|^2 per FRF
};

// Builds the real stacked basis [Re C; Im C] per segment. want_b adds the 2N derivative columns.
void BuildBasis(const Problem& pr, const std::vector<cd>& lambda, bool want_b, std::vector<Eigen::MatrixXd>* basis,
                Eigen::VectorXd* col_scale) {
  const int nm = pr.n_modes, p = pr.p;
  const int cols = p + (want_b ? 2 * nm : 0);
  Eigen::MatrixXcd c(pr.n, cols);
  for (int f = 0; f < pr.n; ++f) {
    const cd jw(0.0, pr.omega[f]);
    const cd fac = pr.k_pow == 0 ? cd(1.0) : pr.k_pow == 1 ? jw : jw * jw;
    for (int r = 0; r < nm; ++r) {
      const cd g = 1.0 / (jw - lambda[r]), gt = 1.0 / (jw - std::conj(lambda[r]));
      c(f, 2 * r) = fac * (g + gt);
      c(f, 2 * r + 1) = fac * cd(0.0, 1.0) * (g - gt);
      if (want_b) {
        const cd q = g * g, qt = gt * gt;
        c(f, p + 2 * r) = fac * (q + qt);
        c(f, p + 2 * r + 1) = fac * cd(0.0, 1.0) * (q - qt);
      }
    }
    int col = 2 * nm;
    if (pr.lower) c(f, col++) = fac / (jw * jw);
    if (pr.upper) c(f, col++) = fac;
  }
  col_scale->resize(p);
  for (int k = 0; k < p; ++k) {
    const double norm = c.col(k).norm();
    (*col_scale)[k] = norm > 0.0 ? 1.0 / norm : 1.0;
    c.col(k) *= (*col_scale)[k];
  }
  const int S = pr.Segments();
  basis->resize(S);
  for (int s = 0; s < S; ++s) {
    const int a = pr.seg_start[s], len = pr.seg_start[s + 1] - a;
    Eigen::MatrixXd& b = (*basis)[s];
    b.resize(2 * len, cols);
    b.topRows(len) = c.middleRows(a, len).real();
    b.bottomRows(len) = c.middleRows(a, len).imag();
  }
}

// `reweight` (one segment only): each FRF's weight is replaced by the one its own residual at these
// poles gives (2/var, var = sse/(n - p/2)); with one segment the solution x does not depend on
// the FRF's weight, so this is exact in a single pass.
Evaluation EvaluateModel(const Problem& pr, const std::vector<cd>& lambda, bool want_jacobian, bool want_std = false,
                         bool reweight = false) {
  Evaluation ev;
  const int nm = pr.n_modes, p = pr.p, S = pr.Segments();
  const int cols = p + (want_jacobian ? 2 * nm : 0);
  std::vector<Eigen::MatrixXd> basis;
  Eigen::VectorXd scale;
  BuildBasis(pr, lambda, want_jacobian, &basis, &scale);
  if (pr.progress && pr.progress->Report()) return ev;  // cancelled: not ok
  std::vector<Eigen::MatrixXd> gram(S), proj(S);
  for (int s = 0; s < S; ++s) {
    gram[s] = Eigen::MatrixXd::Zero(cols, cols);
    gram[s].selfadjointView<Eigen::Lower>().rankUpdate(basis[s].transpose());
    gram[s].triangularView<Eigen::StrictlyUpper>() = gram[s].transpose();
    proj[s].resize(cols, pr.n_frf);  // filled per thread block below: basis^T × data
  }
  if (pr.progress && pr.progress->Report()) return ev;
  ev.x.resize(p, pr.n_frf);
  if (want_std) ev.x_std.resize(p, pr.n_frf);
  ev.frf_sse.resize(pr.n_frf);
  const int threads = std::max(1, std::min(pr.threads, pr.n_frf));
  std::vector<Eigen::MatrixXd> jtj(threads, Eigen::MatrixXd::Zero(2 * nm, 2 * nm));
  std::vector<Eigen::VectorXd> jtr(threads, Eigen::VectorXd::Zero(2 * nm));
  std::vector<double> cost(threads, 0.0);
  std::vector<int> failed(threads, 0);
  auto work = [&](int t, const std::atomic<bool>& stop) {
    // Contiguous FRF block per thread: its share of the data products is one GEMM per segment.
    const int c0 = static_cast<int>(static_cast<long long>(t) * pr.n_frf / threads);
    const int c1 = static_cast<int>(static_cast<long long>(t + 1) * pr.n_frf / threads);
    for (int s = 0; s < S; ++s)
      proj[s].middleCols(c0, c1 - c0).noalias() = basis[s].transpose() * pr.h_real[s].middleCols(c0, c1 - c0);
    Eigen::MatrixXd gw(cols, cols), m_mix = Eigen::MatrixXd::Zero(2 * nm, 2 * nm);
    Eigen::VectorXd vw(cols);
    for (int c = c0; c < c1 && !stop.load(std::memory_order_relaxed); ++c) {
      gw.setZero();
      vw.setZero();
      double hhw = 0.0, hh = 0.0;
      for (int s = 0; s < S; ++s) {
        const double w = pr.w(s, c);
        gw.noalias() += w * gram[s];
        vw.noalias() += w * proj[s].col(c);
        hhw += w * pr.hh(s, c);
        hh += pr.hh(s, c);
      }
      Eigen::LLT<Eigen::MatrixXd> llt(gw.topLeftCorner(p, p));
      if (llt.info() != Eigen::Success) {
        ++failed[t];
        continue;
      }
      const Eigen::VectorXd xs = llt.solve(vw.head(p));
      ev.x.col(c) = scale.cwiseProduct(xs);
      // Unweighted residual energy (for the residual-based noise estimate).
      {
        Eigen::MatrixXd g0 = Eigen::MatrixXd::Zero(p, p);
        Eigen::VectorXd v0 = Eigen::VectorXd::Zero(p);
        for (int s = 0; s < S; ++s) {
          g0 += gram[s].topLeftCorner(p, p);
          v0 += proj[s].col(c).head(p);
        }
        ev.frf_sse[c] = std::max(0.0, hh - 2.0 * xs.dot(v0) + xs.dot(g0 * xs));
      }
      double factor = 1.0;  // new weight / weight used above
      if (reweight && S == 1 && ev.frf_sse[c] > 0.0 && pr.w(0, c) > 0.0)
        factor = 2.0 * std::max(1.0, pr.n - 0.5 * p) / ev.frf_sse[c] / pr.w(0, c);
      cost[t] += factor * std::max(0.0, hhw - xs.dot(vw.head(p)));
      if (want_std) {
        const Eigen::MatrixXd inv = llt.solve(Eigen::MatrixXd::Identity(p, p));
        ev.x_std.col(c) = scale.cwiseProduct(inv.diagonal().cwiseMax(0.0).cwiseSqrt()) / std::sqrt(factor);
      }
      if (!want_jacobian) continue;
      const Eigen::VectorXd& x = ev.x.col(c);
      for (int r = 0; r < nm; ++r) {
        const double xa = x[2 * r], xb = x[2 * r + 1];
        // column 2r = d/dRe(lambda): xa beta1 + xb beta2; column 2r+1 = d/dIm: -xb beta1 + xa beta2
        m_mix(2 * r, 2 * r) = xa;
        m_mix(2 * r + 1, 2 * r) = xb;
        m_mix(2 * r, 2 * r + 1) = -xb;
        m_mix(2 * r + 1, 2 * r + 1) = xa;
      }
      const Eigen::MatrixXd gab_m = gw.block(0, p, p, 2 * nm) * m_mix;  // <A, d>
      const Eigen::MatrixXd dd = m_mix.transpose() * gw.block(p, p, 2 * nm, 2 * nm) * m_mix;
      jtj[t].noalias() += factor * (dd - gab_m.transpose() * llt.solve(gab_m));
      const Eigen::VectorXd de = vw.tail(2 * nm) - gw.block(p, 0, 2 * nm, p) * xs;  // <B, e>
      jtr[t].noalias() -= factor * (m_mix.transpose() * de);
    }
  };
  RunOnThreads(threads, work);
  for (int t = 0; t < threads; ++t) {
    if (failed[t]) return ev;
    ev.cost += cost[t];
    if (want_jacobian) {
      if (t == 0) {
        ev.jtj = jtj[0];
        ev.jtr = jtr[0];
      } else {
        ev.jtj += jtj[t];
        ev.jtr += jtr[t];
      }
    }
  }
  ev.ok = std::isfinite(ev.cost);
  return ev;
}

std::vector<cd> ToLambda(const double* theta, int nm) {
  std::vector<cd> lambda(nm);
  for (int r = 0; r < nm; ++r) lambda[r] = {theta[2 * r], theta[2 * r + 1]};
  return lambda;
}

// The reduced problem handed to Ceres: 2N parameters, 2N + 1 "compressed" residuals [q; rho]
// with jacobian [R; 0], where R^T R = J^T J, R^T q = J^T r and |q|^2 + rho^2 = |r|^2. Gauss-Newton
// and Levenberg-Marquardt steps, the model cost change and the cost are those of the full
// (variable-projection) problem; the 2·n_lines·n_frf residuals are never stored.
class CompressedVarProCost : public ceres::CostFunction {
 public:
  explicit CompressedVarProCost(const Problem* problem) : problem_(problem) {
    set_num_residuals(2 * problem->n_modes + 1);
    mutable_parameter_block_sizes()->push_back(2 * problem->n_modes);
  }

  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    const int nm = problem_->n_modes, k = 2 * nm;
    const std::vector<cd> lambda = ToLambda(parameters[0], nm);
    for (const cd& l : lambda)
      if (!(l.imag() > 0.0) || !std::isfinite(l.real())) return false;
    const bool want_j = jacobians != nullptr && jacobians[0] != nullptr;
    Eigen::Map<Eigen::VectorXd> res(residuals, k + 1);
    if (!want_j) {  // cost only (a trial step): any vector of the right norm
      const Evaluation ev = EvaluateModel(*problem_, lambda, false);
      if (!ev.ok) return false;
      res.setZero();
      res[k] = std::sqrt(ev.cost);
      return true;
    }
    const Evaluation ev = EvaluateModel(*problem_, lambda, true);
    if (!ev.ok) return false;
    Eigen::MatrixXd jtj = ev.jtj;
    const double ridge = 1e-14 * std::max(1e-300, jtj.diagonal().cwiseAbs().maxCoeff());
    Eigen::LLT<Eigen::MatrixXd> llt(jtj);
    if (llt.info() != Eigen::Success) {
      jtj.diagonal().array() += ridge;
      llt.compute(jtj);
      if (llt.info() != Eigen::Success) return false;
    }
    const Eigen::VectorXd q = llt.matrixL().solve(ev.jtr);
    res.head(k) = q;
    res[k] = std::sqrt(std::max(0.0, ev.cost - q.squaredNorm()));
    Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> jac(jacobians[0], k + 1, k);
    jac.setZero();
    jac.topRows(k) = llt.matrixU();
    return true;
  }

 private:
  const Problem* problem_;
};

struct SolveOutcome {
  double initial_cost = kNaN;  // sum of squares (2 × Ceres' cost)
  double final_cost = kNaN;
  bool ok = false;
  bool converged = false;
  int iterations = 0;
  std::string message;
};

// Where each pole may go: a box around its start (real and imaginary parts within `shift` of it,
// the real part below zero) with the imaginary part inside the fitted band. A pole cannot wander
// off to another mode or out of the band; one that ends on the box's edge is reported.
struct PoleBox {
  double re_lo, re_hi, im_lo, im_hi;
};

// After each Levenberg-Marquardt iteration: the share of the iteration limit used; aborts the solve
// once the progress callback has thrown (in an evaluation of this iteration, or now).
class ProgressEachIteration : public ceres::IterationCallback {
 public:
  ProgressEachIteration(RefineProgress* progress, int max_iterations)
      : progress_(progress), max_iterations_(std::max(1, max_iterations)) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& summary) override {
    return progress_->Report(std::min(1.0, static_cast<double>(summary.iteration) / max_iterations_))
               ? ceres::SOLVER_ABORT
               : ceres::SOLVER_CONTINUE;
  }

 private:
  RefineProgress* progress_;
  int max_iterations_;
};

SolveOutcome SolveWithCeres(const Problem& pr, const MlRefineOptions& options, const std::vector<PoleBox>& boxes,
                            std::vector<cd>* lambda) {
  const int nm = pr.n_modes;
  std::vector<double> theta(2 * nm);
  for (int r = 0; r < nm; ++r) {
    theta[2 * r] = (*lambda)[r].real();
    theta[2 * r + 1] = (*lambda)[r].imag();
  }
  ceres::Problem::Options problem_options;
  problem_options.cost_function_ownership = ceres::TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  problem.AddResidualBlock(new CompressedVarProCost(&pr), nullptr, theta.data());
  for (int r = 0; r < nm && r < static_cast<int>(boxes.size()); ++r) {
    problem.SetParameterLowerBound(theta.data(), 2 * r, boxes[r].re_lo);
    problem.SetParameterUpperBound(theta.data(), 2 * r, boxes[r].re_hi);
    problem.SetParameterLowerBound(theta.data(), 2 * r + 1, boxes[r].im_lo);
    problem.SetParameterUpperBound(theta.data(), 2 * r + 1, boxes[r].im_hi);
  }
  ceres::Solver::Options solver;
  solver.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  solver.linear_solver_type = ceres::DENSE_QR;
  solver.max_num_iterations = options.max_iterations;
  solver.function_tolerance = options.function_tolerance;
  solver.parameter_tolerance = options.parameter_tolerance;
  solver.gradient_tolerance = 1e-14;
  solver.num_threads = 1;
  solver.logging_type = ceres::SILENT;
  solver.minimizer_progress_to_stdout = false;
  QuietSolverLogging();
  ProgressEachIteration each_iteration(pr.progress, options.max_iterations);
  if (pr.progress) solver.callbacks.push_back(&each_iteration);
  ceres::Solver::Summary summary;
  ceres::Solve(solver, &problem, &summary);
  if (pr.progress) pr.progress->RethrowIfThrown();
  SolveOutcome out;
  out.iterations = static_cast<int>(summary.iterations.size());
  out.initial_cost = 2.0 * summary.initial_cost;
  out.final_cost = 2.0 * summary.final_cost;
  out.message = summary.message;
  out.ok = summary.IsSolutionUsable();
  out.converged = summary.termination_type == ceres::CONVERGENCE;
  if (out.ok) *lambda = ToLambda(theta.data(), nm);
  return out;
}

}  // namespace

std::string RefineMethodToString(RefineMethod method) { return NameOf(kRefineMethodNames, method); }

bool StringToRefineMethod(const std::string& text, RefineMethod* method) {
  return FromName(kRefineMethodNames, text, method);
}

std::string NoiseSourceToString(NoiseSource source) {
  return source == NoiseSource::kCoherence ? "coherence" : "residual";
}

std::string RefineTerminationToString(RefineTermination termination) {
  switch (termination) {
    case RefineTermination::kConverged: return "converged";
    case RefineTermination::kNoConvergence: return "no_convergence";
    case RefineTermination::kRejected: return "rejected";
    case RefineTermination::kFailed: return "failed";
  }
  return "failed";
}

bool MlRefineOptions::IsValid(std::string* error) const {
  auto fail = [&](const std::string& m) {
    if (error) *error = m;
    return false;
  };
  if (!(max_reduced_chi2 > 0.0)) return fail("max_reduced_chi2 must be > 0");
  if (max_iterations < 1) return fail("max_iterations (" + std::to_string(max_iterations) + ") must be >= 1");
  if (!(function_tolerance > 0.0)) return fail("function_tolerance must be > 0");
  if (!(parameter_tolerance > 0.0)) return fail("parameter_tolerance must be > 0");
  if (noise_segments < 1) return fail("noise_segments (" + std::to_string(noise_segments) + ") must be >= 1");
  if (!(max_pole_shift_bandwidths > 0.0)) return fail("max_pole_shift_bandwidths must be > 0");
  if (threads < 0) return fail("threads must be >= 0");
  return true;
}

std::string MlRefineSummary::BriefReport() const {
  std::ostringstream s;
  if (uncertainty_only) {
    s << "no refinement (--refine none): sigma of the PolyMAX poles from the Fisher information, noise from "
      << NoiseSourceToString(noise_source) << ", reduced chi2 " << reduced_chi2;
    return s.str();
  }
  s << "ML refinement: " << RefineTerminationToString(termination) << ", " << iterations << " iterations, noise from "
    << NoiseSourceToString(noise_source) << ", cost " << initial_cost << " -> " << final_cost << ", reduced chi2 "
    << reduced_chi2;
  if (!message.empty()) s << " (" << message << ")";
  return s.str();
}

void PoleStdToFrequencyAndDamping(std::complex<double> lambda, const Eigen::Matrix2d& covariance,
                                  double* frequency_std_hz, double* damping_ratio_std) {
  const double u = lambda.real(), v = lambda.imag(), a = std::abs(lambda);
  if (!(a > 0.0) || !covariance.allFinite()) {
    *frequency_std_hz = *damping_ratio_std = kNaN;
    return;
  }
  const Eigen::Vector2d gf(u / (kTwoPi * a), v / (kTwoPi * a));
  const Eigen::Vector2d gz(-v * v / (a * a * a), u * v / (a * a * a));
  *frequency_std_hz = std::sqrt(std::max(0.0, gf.dot(covariance * gf)));
  *damping_ratio_std = std::sqrt(std::max(0.0, gz.dot(covariance * gz)));
}

MlRefineResult RefineModalModel(const FitData& data, const std::vector<SelectedPole>& poles,
                                const MlRefineOptions& options, const ProgressCallback& progress) {
  std::string why;
  if (!options.IsValid(&why)) throw std::invalid_argument("MlRefineOptions: " + why);
  RefineProgress refine_progress(progress);
  if (refine_progress.Report(0.0)) refine_progress.RethrowIfThrown();
  const double t0 = ThreadCpuSeconds();
  const int nm = static_cast<int>(poles.size());
  const int l = data.OutputCount(), m = data.ReferenceCount(), n_frf = l * m;
  MlRefineResult result;
  result.poles.resize(nm);
  for (int r = 0; r < nm; ++r) {
    RefinedPole& rp = result.poles[r];
    rp.lambda_fitted = poles[r].pole.lambda_fitted;
    rp.lambda = poles[r].pole.lambda;
    rp.frequency_hz = poles[r].pole.frequency_hz;
    rp.damping_ratio = poles[r].pole.damping_ratio;
  }
  if (nm == 0) {
    result.summary.termination = RefineTermination::kFailed;
    result.summary.message = "no poles to refine";
    return result;
  }

  Problem pr;
  pr.n_frf = n_frf;
  pr.n_modes = nm;
  pr.lower = options.lower_residual;
  pr.upper = options.upper_residual;
  pr.p = 2 * nm + (pr.lower ? 1 : 0) + (pr.upper ? 1 : 0);
  pr.k_pow = data.frf_type == FrfType::kReceptance ? 0 : data.frf_type == FrfType::kMobility ? 1 : 2;
  pr.threads = options.threads > 0 ? options.threads : std::max(1u, std::thread::hardware_concurrency());
  if (progress) pr.progress = &refine_progress;
  std::vector<int> used;
  for (int k = 0; k < data.LineCount(); ++k)
    if (data.line_weight[k] != 0.0) used.push_back(k);
  pr.n = static_cast<int>(used.size());
  if (2 * pr.n < pr.p + 2)
    throw InputError("ml refinement", "too few valid lines (" + std::to_string(pr.n) + ") for " + std::to_string(nm) +
                                          " modes");
  pr.omega.resize(pr.n);
  for (int k = 0; k < pr.n; ++k) pr.omega[k] = kTwoPi * data.frequency_hz[used[k]];

  // Noise model: coherence (pooled per segment) when every FRF has it, else residual-based.
  bool coherence = options.use_coherence && data.noise_variance.rows() == data.LineCount() &&
                   data.noise_variance.cols() == n_frf;
  int segments = 1;
  Eigen::MatrixXd seg_var;
  if (coherence) {
    segments = std::max(1, std::min(options.noise_segments, pr.n / 8));
    pr.seg_start.resize(segments + 1);
    for (int s = 0; s <= segments; ++s) pr.seg_start[s] = static_cast<int>(static_cast<long long>(s) * pr.n / segments);
    seg_var.resize(segments, n_frf);
    for (int c = 0; c < n_frf && coherence; ++c) {
      double fallback = 0.0;
      int fallback_n = 0;
      for (int s = 0; s < segments; ++s) {
        double sum = 0.0;
        int cnt = 0;
        for (int k = pr.seg_start[s]; k < pr.seg_start[s + 1]; ++k) {
          const double v = data.noise_variance(used[k], c);
          if (std::isfinite(v) && v > 0.0) sum += v, ++cnt;
        }
        seg_var(s, c) = cnt > 0 ? sum / cnt : kNaN;
        if (cnt > 0) fallback += sum, fallback_n += cnt;
      }
      if (fallback_n == 0) {
        coherence = false;  // an FRF without usable coherence: fall back for the whole set
        break;
      }
      for (int s = 0; s < segments; ++s)
        if (!std::isfinite(seg_var(s, c))) seg_var(s, c) = fallback / fallback_n;
      // Floor: a segment of near-perfect coherence must not take all the weight.
      const double floor = 1e-4 * seg_var.col(c).maxCoeff();
      seg_var.col(c) = seg_var.col(c).cwiseMax(floor);
    }
  }
  if (!coherence) {
    segments = 1;
    pr.seg_start = {0, pr.n};
  }
  result.summary.noise_source = coherence ? NoiseSource::kCoherence : NoiseSource::kResidual;
  const int S = segments;
  pr.h_real.resize(S);
  pr.hh.resize(S, n_frf);
  for (int s = 0; s < S; ++s) {
    const int a = pr.seg_start[s], len = pr.seg_start[s + 1] - a;
    Eigen::MatrixXd& hr = pr.h_real[s];
    hr.resize(2 * len, n_frf);
    for (int c = 0; c < n_frf; ++c)
      for (int k = 0; k < len; ++k) {
        const cd h = data.h(used[a + k], c);
        hr(k, c) = h.real();
        hr(len + k, c) = h.imag();
      }
    pr.hh.row(s) = hr.colwise().squaredNorm();
  }
  // Residual-based variance per FRF: E|e|^2 = sse / (n - p/2) (p real unknowns per FRF).
  auto residual_weights = [&](const Evaluation& ev) {
    pr.w.resize(1, n_frf);
    for (int c = 0; c < n_frf; ++c) {
      const double var = ev.frf_sse[c] / std::max(1.0, pr.n - 0.5 * pr.p);
      pr.w(0, c) = var > 0.0 ? 2.0 / var : 0.0;
    }
    const double wmax = pr.w.maxCoeff();
    if (wmax > 0.0)  // an exact FRF (zero residual) gets the largest finite weight, not infinity
      for (int c = 0; c < n_frf; ++c)
        if (!(pr.w(0, c) > 0.0) || !std::isfinite(pr.w(0, c))) pr.w(0, c) = wmax;
  };

  std::vector<cd> lambda0(nm);
  for (int r = 0; r < nm; ++r) lambda0[r] = poles[r].pole.lambda_fitted;
  if (coherence) {
    pr.w = (2.0 / seg_var.array()).matrix();
  } else {
    pr.w = Eigen::MatrixXd::Ones(1, n_frf);
    const Evaluation first = EvaluateModel(pr, lambda0, false);
    refine_progress.RethrowIfThrown();
    if (!first.ok) {
      result.summary.termination = RefineTermination::kFailed;
      result.summary.message = "singular residue problem at the PolyMAX poles";
      return result;
    }
    residual_weights(first);
    if (!(pr.w.maxCoeff() > 0.0)) pr.w.setOnes();  // noise-free data: plain LS
  }

  std::vector<cd> lambda = lambda0;
  // Each pole's neighbourhood: max_pole_shift_bandwidths half-power bandwidths (or its
  // stabilisation spread, if wider) around its start, its frequency inside the band.
  std::vector<PoleBox> boxes(nm);
  const double band_lo = kTwoPi * data.frequency_hz[0], band_hi = kTwoPi * data.frequency_hz[data.LineCount() - 1];
  for (int r = 0; r < nm; ++r) {
    const double w0 = std::abs(lambda0[r]), z0 = -lambda0[r].real() / w0;
    const double shift = std::max(options.max_pole_shift_bandwidths * 2.0 * std::max(z0, 1e-4) * w0,
                                  3.0 * kTwoPi * (std::isfinite(poles[r].frequency_spread_hz) ? poles[r].frequency_spread_hz : 0.0));
    boxes[r] = {lambda0[r].real() - shift, std::min(lambda0[r].real() + shift, -1e-9 * w0),
                std::max(lambda0[r].imag() - shift, std::min(band_lo, lambda0[r].imag())),
                std::min(lambda0[r].imag() + shift, std::max(band_hi, lambda0[r].imag()))};
  }
  SolveOutcome outcome;
  if (options.estimate_only) {
    outcome.ok = outcome.converged = true;
    outcome.message = "poles kept (uncertainty only)";
    result.summary.uncertainty_only = true;
  } else {
    outcome = SolveWithCeres(pr, options, boxes, &lambda);
  }
  int iterations = outcome.iterations;
  result.summary.initial_cost = outcome.initial_cost;
  // The residual-based variance is re-estimated at the refined poles (the PolyMAX poles' misfit
  // includes their bias) for the covariance: the final evaluation reweights. The weights only shape
  // the estimator's efficiency, so the fit is not repeated with them.
  const bool reweight = outcome.ok && !coherence && !options.estimate_only;
  result.summary.iterations = iterations;

  // Plausibility: every pole stable, 0 < zeta < 1, and not moved by more than a few half-power
  // bandwidths (a pole that wanders off has found another mode or the noise).
  bool plausible = outcome.ok;
  std::ostringstream reason;
  if (!outcome.ok)
    reason << "the modal model could not be evaluated at the PolyMAX poles or on the way from them (an unstable or "
              "doubled pole?); solver: " << outcome.message;
  for (int r = 0; r < nm && plausible; ++r) {
    const double f0 = std::abs(lambda0[r]), z0 = -lambda0[r].real() / f0;
    const double bandwidth = 2.0 * std::max(z0, 1e-4) * f0;
    const PoleBox& b = boxes[r];
    const double edge = 1e-6 * f0;
    const bool on_edge = lambda[r].real() <= b.re_lo + edge || lambda[r].imag() <= b.im_lo + edge ||
                         lambda[r].imag() >= b.im_hi - edge;
    if (!(lambda[r].real() < 0.0) || !(lambda[r].imag() > 0.0)) {
      plausible = false;
      reason << "pole " << r + 1 << " became unstable";
    } else if (on_edge) {
      plausible = false;
      reason << "the pole at " << f0 / kTwoPi << " Hz was pressed against the edge of its neighbourhood ("
             << options.max_pole_shift_bandwidths << " half-power bandwidths, inside the band): the data pull it "
             << "towards another mode or out of the band";
    } else if (std::abs(lambda[r] - lambda0[r]) > options.max_pole_shift_bandwidths * bandwidth * std::sqrt(2.0)) {
      plausible = false;
      reason << "pole at " << f0 / kTwoPi << " Hz moved by " << std::abs(lambda[r] - lambda0[r]) / bandwidth
             << " half-power bandwidths";
    }
  }
  result.summary.poles_plausible = plausible;
  if (plausible && coherence && !options.estimate_only) {
    const double dof_ = 2.0 * pr.n * n_frf - (static_cast<double>(pr.p) * n_frf + 2.0 * nm);
    const double chi2 = dof_ > 0 ? outcome.final_cost / dof_ : kNaN;
    if (!(chi2 <= options.max_reduced_chi2)) {
      plausible = false;
      reason << "misfit " << chi2 << " times the coherence noise level (above " << options.max_reduced_chi2
             << "): the modal model does not describe these data to their noise level";
    }
  }
  if (!plausible) lambda = lambda0;

  // Final evaluation: residues, their sigma, and the Fisher information of the poles.
  const Evaluation fin = EvaluateModel(pr, lambda, true, true, reweight && plausible);
  refine_progress.RethrowIfThrown();
  result.summary.final_cost = fin.ok ? fin.cost : kNaN;
  if (!std::isfinite(result.summary.initial_cost)) result.summary.initial_cost = result.summary.final_cost;
  const double dof = 2.0 * pr.n * n_frf - (static_cast<double>(pr.p) * n_frf + 2.0 * nm);
  result.summary.reduced_chi2 = fin.ok && dof > 0 ? fin.cost / dof : kNaN;
  result.summary.termination = !plausible ? (outcome.ok ? RefineTermination::kRejected : RefineTermination::kFailed)
                               : outcome.converged ? RefineTermination::kConverged
                                                   : RefineTermination::kNoConvergence;
  result.summary.message = plausible ? outcome.message : reason.str();

  // The data's own noise level scales the covariance (the noise model is known up to a factor).
  const double scale = std::isfinite(result.summary.reduced_chi2) ? result.summary.reduced_chi2 : 1.0;
  Eigen::MatrixXd cov = Eigen::MatrixXd::Constant(2 * nm, 2 * nm, kNaN);
  if (fin.ok) {
    Eigen::FullPivLU<Eigen::MatrixXd> lu(fin.jtj);
    if (lu.isInvertible()) cov = scale * lu.inverse();
  }
  const double decay = data.window_decay_rate;
  result.residues.resize(n_frf, nm);
  result.residue_std = Eigen::MatrixXd::Constant(n_frf, nm, kNaN);
  result.lower_residual = Eigen::VectorXd::Zero(n_frf);
  result.upper_residual = Eigen::VectorXd::Zero(n_frf);
  for (int r = 0; r < nm; ++r) {
    RefinedPole& rp = result.poles[r];
    rp.lambda_fitted = lambda[r];
    rp.lambda = lambda[r] + decay;
    PoleToFrequencyAndDamping(rp.lambda, &rp.frequency_hz, &rp.damping_ratio);
    rp.covariance = cov.block<2, 2>(2 * r, 2 * r);
    PoleStdToFrequencyAndDamping(rp.lambda, rp.covariance, &rp.frequency_std_hz, &rp.damping_ratio_std);
    rp.residue_dof = 2 * n_frf;
  }
  if (fin.ok) {
    for (int c = 0; c < n_frf; ++c) {
      // Weight of this FRF's unit-variance residuals (segment-averaged): sigma of x from (A^T W A)^-1.
      for (int r = 0; r < nm; ++r) {
        const double xa = fin.x(2 * r, c), xb = fin.x(2 * r + 1, c);
        result.residues(c, r) = {xa, xb};
        const double sa = fin.x_std(2 * r, c) * std::sqrt(scale), sb = fin.x_std(2 * r + 1, c) * std::sqrt(scale);
        result.residue_std(c, r) = std::sqrt(0.5 * (sa * sa + sb * sb));
        if (sa > 0.0 && sb > 0.0) result.poles[r].residue_chi2 += xa * xa / (sa * sa) + xb * xb / (sb * sb);
      }
      int col = 2 * nm;
      if (pr.lower) result.lower_residual[c] = fin.x(col++, c);
      if (pr.upper) result.upper_residual[c] = fin.x(col++, c);
    }
  }
  result.summary.seconds = ThreadCpuSeconds() - t0;
  refine_progress.Report(1.0);
  refine_progress.RethrowIfThrown();
  return result;
}

}  // namespace ema::curvefit
