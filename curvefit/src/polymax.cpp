// pLSCF / PolyMAX. Layout of the unknowns follows algorithms.md §2.2: alpha = [alpha_0; ..;
// alpha_p] (m×m blocks), basis Omega = exp(-j w dt), constraint alpha_p = I.
#include "ema/curvefit/polymax.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <mutex>
#include <thread>
#include <time.h>

#include "ema/core/error.hpp"
#include "ema/core/parallel.hpp"
#include "ema/frf/fft.hpp"

namespace ema::curvefit {

namespace {

using Clock = std::chrono::steady_clock;
double Seconds(Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double>(b - a).count(); }

/// Lags -P..P of sum_n x_n Omega_n^k, all series at once through one FFT each (§2.5).
/// With f_n = f0 + n df and dt = 1/(N' df): Omega_n^k = exp(-j2pi f0 dt k) exp(-j2pi n k/N').
class LagSums {
 public:
  LagSums(int fft_length, int lines, double phase_per_lag)
      : fft_(fft_length), lines_(lines), phase_per_lag_(phase_per_lag) {}

  /// out[k + P] = sum_n x[n] Omega_n^k for k = -P..P.
  void Compute(const Eigen::VectorXcd& x, int max_lag, Eigen::VectorXcd* out) {
    const int n_fft = fft_.size();
    std::complex<double>* buffer = fft_.data();
    for (int n = 0; n < n_fft; ++n) buffer[n] = n < lines_ ? x[n] : std::complex<double>(0.0, 0.0);
    fft_.Execute();
    out->resize(2 * max_lag + 1);
    for (int k = -max_lag; k <= max_lag; ++k) {
      const int idx = ((k % n_fft) + n_fft) % n_fft;
      (*out)[k + max_lag] = buffer[idx] * std::polar(1.0, -phase_per_lag_ * k);
    }
  }

 private:
  frf::ComplexFft fft_;
  int lines_;
  double phase_per_lag_;
};

/// Cholesky of a symmetric positive (semi)definite matrix that stops where a pivot collapses;
/// returns the size of the well-conditioned leading block. Leading blocks of L are the factors
/// of the leading blocks of R, which is what lets one factorisation serve every order.
int PartialCholesky(const Eigen::MatrixXd& r, Eigen::MatrixXd* l_out) {
  const int n = static_cast<int>(r.rows());
  Eigen::MatrixXd& l = *l_out;
  l.setZero(n, n);
  const double scale = r.diagonal().maxCoeff();
  for (int j = 0; j < n; ++j) {
    double d = r(j, j) - l.row(j).head(j).squaredNorm();
    if (!(d > 1e-13 * scale)) return j;
    l(j, j) = std::sqrt(d);
    for (int i = j + 1; i < n; ++i) l(i, j) = (r(i, j) - l.row(i).head(j).dot(l.row(j).head(j))) / l(j, j);
  }
  return n;
}

// Eigenvalues of a real upper Hessenberg matrix by the Francis double-shift QR iteration
// (Golub & Van Loan, Alg. 7.5.1-7.5.2), eigenvalues only: every similarity is applied to the
// active (undeflated) window alone. Returns false when it does not converge.
bool HessenbergEigenvalues(Eigen::MatrixXd& h, Eigen::VectorXcd* out) {
  const int n = static_cast<int>(h.rows());
  Eigen::VectorXcd& ev = *out;
  ev.resize(n);
  const double eps = std::numeric_limits<double>::epsilon();
  int iu = n - 1, iter = 0;
  while (iu >= 0) {
    int il = iu;
    while (il > 0) {
      double s = std::abs(h(il - 1, il - 1)) + std::abs(h(il, il));
      if (s == 0.0) s = h.block(0, 0, iu + 1, iu + 1).cwiseAbs().maxCoeff();
      if (std::abs(h(il, il - 1)) <= eps * s) {
        h(il, il - 1) = 0.0;
        break;
      }
      --il;
    }
    if (il == iu) {
      ev[iu] = h(iu, iu);
      --iu;
      iter = 0;
      continue;
    }
    if (il == iu - 1) {
      const double a = h(iu - 1, iu - 1), b = h(iu - 1, iu), c = h(iu, iu - 1), d = h(iu, iu);
      const double p = 0.5 * (a - d), disc = p * p + b * c;
      if (disc >= 0.0) {
        const double z = p + std::copysign(std::sqrt(disc), p);
        ev[iu - 1] = d + z;
        ev[iu] = z != 0.0 ? d - b * c / z : d;
      } else {
        const double w = std::sqrt(-disc);
        ev[iu - 1] = std::complex<double>(d + p, w);
        ev[iu] = std::complex<double>(d + p, -w);
      }
      iu -= 2;
      iter = 0;
      continue;
    }
    if (++iter > 60) return false;
    double s, t;
    if (iter % 11 == 10) {  // exceptional shift against cycling
      const double x = std::abs(h(iu, iu - 1)) + std::abs(h(iu - 1, iu - 2));
      s = 1.5 * x;
      t = x * x;
    } else {
      s = h(iu - 1, iu - 1) + h(iu, iu);
      t = h(iu - 1, iu - 1) * h(iu, iu) - h(iu - 1, iu) * h(iu, iu - 1);
    }
    double x = h(il, il) * h(il, il) + h(il, il + 1) * h(il + 1, il) - s * h(il, il) + t;
    double y = h(il + 1, il) * (h(il, il) + h(il + 1, il + 1) - s);
    double z = h(il + 1, il) * h(il + 2, il + 1);
    for (int k = il; k <= iu - 2; ++k) {
      const double nrm = std::sqrt(x * x + y * y + z * z);
      if (nrm != 0.0) {
        const double alpha = x > 0 ? -nrm : nrm;
        const double v0 = x - alpha, v1 = y, v2 = z;
        const double beta = 2.0 / (v0 * v0 + v1 * v1 + v2 * v2);
        const int q = std::max(il, k - 1);
        for (int j = q; j <= iu; ++j) {
          const double sj = beta * (v0 * h(k, j) + v1 * h(k + 1, j) + v2 * h(k + 2, j));
          h(k, j) -= sj * v0;
          h(k + 1, j) -= sj * v1;
          h(k + 2, j) -= sj * v2;
        }
        if (k > il) h(k + 1, k - 1) = h(k + 2, k - 1) = 0.0;
        const int r = std::min(k + 3, iu);
        double* c0 = &h(0, k);
        double* c1 = &h(0, k + 1);
        double* c2 = &h(0, k + 2);
        for (int i = il; i <= r; ++i) {
          const double si = beta * (c0[i] * v0 + c1[i] * v1 + c2[i] * v2);
          c0[i] -= si * v0;
          c1[i] -= si * v1;
          c2[i] -= si * v2;
        }
      }
      x = h(k + 1, k);
      y = h(k + 2, k);
      if (k < iu - 2) z = h(k + 3, k);
    }
    // Final 2-vector reflector on rows/columns iu-1, iu.
    const double nrm = std::hypot(x, y);
    if (nrm != 0.0) {
      const double alpha = x > 0 ? -nrm : nrm;
      const double v0 = x - alpha, v1 = y;
      const double beta = 2.0 / (v0 * v0 + v1 * v1);
      for (int j = std::max(il, iu - 2); j <= iu; ++j) {
        const double sj = beta * (v0 * h(iu - 1, j) + v1 * h(iu, j));
        h(iu - 1, j) -= sj * v0;
        h(iu, j) -= sj * v1;
      }
      if (iu - 2 >= il) h(iu, iu - 2) = 0.0;
      for (int i = il; i <= iu; ++i) {
        const double si = beta * (h(i, iu - 1) * v0 + h(i, iu) * v1);
        h(i, iu - 1) -= si * v0;
        h(i, iu) -= si * v1;
      }
    }
  }
  return true;
}

/// Eigenvalues of the block companion matrix C (size m·p). C^T, with its indices reordered
/// so that k·m + r -> r·p + k, is already upper Hessenberg in its leading p×p block and has only
/// one spike column entering the trailing part; reducing just the trailing block to Hessenberg
/// (and applying that similarity to the rows above) leaves a Hessenberg matrix for the QR
/// iterations. For m = 1 no reduction at all is needed.
Eigen::VectorXcd CompanionEigenvalues(const Eigen::MatrixXd& C, int m, int p) {
  const int n = m * p;
  Eigen::MatrixXd A(n, n);
  for (int j = 0; j < n; ++j) {
    const int cj = (j % p) * m + j / p;
    for (int i = 0; i < n; ++i) A(i, j) = C(cj, (i % p) * m + i / p);  // A = P^T C^T P
  }
  if (m > 1 && p > 1) {
    const int s = p - 1, k = n - s;
    Eigen::HessenbergDecomposition<Eigen::MatrixXd> hd(A.bottomRightCorner(k, k));
    const Eigen::MatrixXd top = A.topRightCorner(s, k) * hd.matrixQ();
    A.topRightCorner(s, k) = top;
    A.bottomRightCorner(k, k) = hd.matrixH();
  }
  for (int j = 0; j < n; ++j)
    for (int i = j + 2; i < n; ++i) A(i, j) = 0.0;  // exact Hessenberg (rounding below)
  Eigen::VectorXcd fast;
  Eigen::MatrixXd work = A;
  if (HessenbergEigenvalues(work, &fast)) return fast;
  Eigen::RealSchur<Eigen::MatrixXd> schur(n);  // fallback: Eigen's Schur form
  schur.computeFromHessenberg(A, Eigen::MatrixXd(), false);
  const Eigen::MatrixXd& T = schur.matrixT();
  Eigen::VectorXcd ev(n);
  for (int i = 0; i < n;) {
    if (i + 1 < n && T(i + 1, i) != 0.0) {  // 2×2 block: a complex pair
      const double half = 0.5 * (T(i, i) - T(i + 1, i + 1));
      const double z = std::sqrt(std::abs(half * half + T(i + 1, i) * T(i, i + 1)));
      ev[i] = {T(i + 1, i + 1) + half, z};
      ev[i + 1] = {T(i + 1, i + 1) + half, -z};
      i += 2;
    } else {
      ev[i] = T(i, i);
      ++i;
    }
  }
  return ev;
}

}  // namespace

double ThreadCpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

FrequencyMap MapBandToUnitCircle(const FitData& data) {
  const int n = data.LineCount();
  const double df = data.line_spacing_hz, f_lo = data.frequency_hz[0], f_hi = data.frequency_hz[n - 1];
  FrequencyMap map;
  // Full band (§2.9): f_hi at angle ~pi, N' = 2 f_hi/df, no aliasing.
  map.fft_length = std::max(static_cast<int>(std::ceil(2.0 * f_hi / df - 1e-9)), n);
  map.dt = 1.0 / (map.fft_length * df);
  const double fraction = (f_hi - f_lo) / f_hi;
  if (!(fraction < kZoomBandFraction) || n < 8) return map;
  // Zoom band: on the full-band map it covers an arc of only fraction·pi, where z^0..z^p are
  // nearly collinear and the normal equations turn singular after a handful of orders (a 2 Hz
  // stepped-sine band at 80 Hz: order 4). A longer dt spreads the band over most of the upper
  // half circle; the frequencies below it wrap round the circle k times (aliasing), which costs
  // nothing because only the band's lines are fitted. The band must land inside (0, pi) so that
  // each in-band pole's conjugate lies outside it: choose N' with the band's start at angle
  // a·2pi and its end at (a + s)·2pi, s = (n-1)/N', inside [0.03, 0.47]; prefer the band centred
  // near pi/2 and spanning as much as possible.
  double best_score = std::numeric_limits<double>::infinity();
  const int lo = static_cast<int>(std::ceil((n - 1) / 0.44)), hi = 6 * (n - 1);
  for (int n_fft = lo; n_fft <= hi; ++n_fft) {
    const double s = (n - 1.0) / n_fft, turns = f_lo / (df * n_fft);
    const double a = turns - std::floor(turns);
    if (a < 0.03 || a + s > 0.47) continue;
    const double score = std::abs(a + 0.5 * s - 0.25) + 0.5 * (0.44 - s);
    if (score < best_score) {
      best_score = score;
      map.fft_length = n_fft;
      map.dt = 1.0 / (n_fft * df);
      map.alias_rad_s = kTwoPi * std::floor(turns) / map.dt;
    }
  }
  return map;
}

int MaxSupportedOrder(const FitData& data) {
  // A polynomial of order p has p+1 real coefficients per numerator; ask for at least as many
  // valid complex lines as that (twice as many real equations), and lags below half the FFT.
  const int lines = data.UsedLineCount();
  const int n_fft = MapBandToUnitCircle(data).fft_length;
  return std::max(0, std::min(lines - 1, (n_fft - 1) / 2));
}

int DefaultOrderMax(const FitData& data) {
  const int m = std::max(1, data.ReferenceCount());
  return std::min((120 + m - 1) / m, MaxSupportedOrder(data));
}

StabilisationDiagram EstimatePoles(const FitData& data, const PolymaxOptions& options,
                                   const ProgressCallback& progress, PolymaxTiming* timing) {
  const auto t0 = Clock::now();
  const double cpu0 = ThreadCpuSeconds();
  const int l = data.OutputCount(), m = data.ReferenceCount(), n = data.LineCount();
  int order_max = options.order_max > 0 ? options.order_max : DefaultOrderMax(data);
  const int supported = MaxSupportedOrder(data);
  if (order_max > supported || supported < 1)
    throw InputError("polymax", "order " + std::to_string(order_max) + " needs at least " +
                                    std::to_string(order_max + 1) + " valid lines in the band, have " +
                                    std::to_string(data.UsedLineCount()) + " (highest usable order " +
                                    std::to_string(supported) + ")");
  const int order_min = std::clamp(options.order_min, 1, order_max);

  StabilisationDiagram diagram;
  diagram.references = m;
  diagram.frequency_hz = data.frequency_hz;
  diagram.band_lo_hz = data.frequency_hz[0];
  diagram.band_hi_hz = data.frequency_hz[n - 1];
  diagram.sum_frf = data.h.cwiseAbs().rowwise().sum();
  diagram.warnings = data.warnings;

  // Frequency normalisation (§2.9): the highest line maps to angle ~pi (a zoom band: most of
  // the upper half circle); dt = 1/(N' df) with an integer FFT length N' so that the lag sums
  // come from FFTs.
  const double f0 = data.frequency_hz[0];
  const FrequencyMap map = MapBandToUnitCircle(data);
  const int n_fft = map.fft_length;
  const double dt = map.dt;
  diagram.zoom_mapped = map.alias_rad_s > 0.0;
  int P = order_max;

  // Weighted data: per-output 1/RMS, skipped lines zeroed (weights may vary per (o, f), §2.5).
  Eigen::MatrixXcd hw(n, l * m);
  for (int o = 0; o < l; ++o)
    for (int i = 0; i < m; ++i)
      hw.col(o * m + i) = data.h.col(o * m + i).cwiseProduct(data.line_weight) * data.output_weight[o];

  // The normal equations report no share (0 until the first order is done), but each FRF's step
  // asks the callback: one that throws (a cancellation) stops a big set's normal equations too.
  const auto step = [&progress] { ReportProgress(progress, 0.0, "poles"); };
  Eigen::VectorXcd r_lag;
  std::vector<Eigen::VectorXcd> s_lag(l * m);     // per (o, i)
  std::vector<Eigen::VectorXcd> t_lag(m * m);     // summed over outputs, per (i, j)
  {
    step();
    LagSums lags(n_fft, n, kTwoPi * f0 * dt);
    lags.Compute(data.line_weight.cast<std::complex<double>>(), P, &r_lag);
    for (int c = 0; c < l * m; ++c) {
      step();
      lags.Compute(hw.col(c), P, &s_lag[c]);
    }
    for (int i = 0; i < m; ++i)
      for (int j = i; j < m; ++j) {
        step();
        Eigen::VectorXcd x = Eigen::VectorXcd::Zero(n);
        for (int o = 0; o < l; ++o) x += hw.col(o * m + i).conjugate().cwiseProduct(hw.col(o * m + j));
        lags.Compute(x, P, &t_lag[i * m + j]);
        if (j != i) {  // t_ji[k] = conj(t_ij[-k])
          t_lag[j * m + i] = t_lag[i * m + j].reverse().conjugate();
        }
      }
  }

  const int lag0 = static_cast<int>(r_lag.size() / 2);  // index of lag 0
  // R (Toeplitz) and its Cholesky factor, once for the highest order.
  Eigen::MatrixXd R(P + 1, P + 1);
  for (int a = 0; a <= P; ++a)
    for (int b = 0; b <= P; ++b) R(a, b) = r_lag[b - a + lag0].real();
  Eigen::MatrixXd L;
  const int good = PartialCholesky(R, &L);
  if (good < P + 1) {
    const int capped = good - 1;
    if (capped < order_min)
      throw InputError("polymax", "the band is too narrow for any model order (normal equations singular)");
    diagram.warnings.push_back("polymax: normal equations become singular above order " + std::to_string(capped) +
                               " (narrow band); orders capped at " + std::to_string(capped));
    P = capped;
    L = L.topLeftCorner(P + 1, P + 1).eval();
  }
  order_max = P;
  const int nc = m * (P + 1);

  // Z_o = L^{-1} S_o, stored by row c (Zrows[c] is l × nc): the numerator is eliminated with
  // M_p = T_p - sum_{c<=p} Z[c]^T Z[c] restricted to the leading m(p+1) block (§2.3), so one
  // triangular solve at P serves every order.
  std::vector<Eigen::MatrixXd> zrows(P + 1, Eigen::MatrixXd(l, nc));
  {
    Eigen::MatrixXd s(P + 1, nc);
    for (int o = 0; o < l; ++o) {
      step();
      for (int a = 0; a <= P; ++a)
        for (int b = 0; b <= P; ++b)
          for (int i = 0; i < m; ++i) s(a, b * m + i) = -s_lag[o * m + i][b - a + lag0].real();
      L.triangularView<Eigen::Lower>().solveInPlace(s);
      for (int c = 0; c <= P; ++c) zrows[c].row(o) = s.row(c);
    }
  }
  Eigen::MatrixXd T(nc, nc);
  for (int a = 0; a <= P; ++a)
    for (int b = 0; b <= P; ++b)
      for (int i = 0; i < m; ++i)
        for (int j = 0; j < m; ++j) T(a * m + i, b * m + j) = t_lag[i * m + j][b - a + lag0].real();

  // Per-order reduced matrices M_p (leading blocks), by rank-l updates of G.
  std::vector<Eigen::MatrixXd> reduced(P + 1);
  {
    Eigen::MatrixXd G = Eigen::MatrixXd::Zero(nc, nc);
    for (int c = 0; c <= P; ++c) {
      step();
      G.selfadjointView<Eigen::Lower>().rankUpdate(zrows[c].transpose());
      if (c >= order_min) {
        const int k = m * (c + 1);
        Eigen::MatrixXd mp = T.topLeftCorner(k, k);
        mp.triangularView<Eigen::Lower>() -= G.topLeftCorner(k, k);
        reduced[c] = mp.selfadjointView<Eigen::Lower>();
      }
    }
  }
  const auto t1 = Clock::now();
  const double cpu1 = ThreadCpuSeconds();

  // Per order: constrained LS solve, companion eigenvalues, participation vectors. Orders are
  // independent here, so they run on a small thread pool.
  const int n_orders = order_max - order_min + 1;
  diagram.orders.assign(n_orders, {});
  diagram.order_min = order_min;
  diagram.order_max = order_max;
  std::atomic<int> next{0};
  std::atomic<int> done{0};
  std::mutex progress_mutex;
  std::vector<double> solve_time, eig_time;
  const int n_threads = std::max(1, std::min(options.threads > 0 ? options.threads
                                                                 : static_cast<int>(std::thread::hardware_concurrency()),
                                             n_orders));
  solve_time.assign(n_threads, 0.0);
  eig_time.assign(n_threads, 0.0);
  const double band_lo = diagram.band_lo_hz, band_hi = diagram.band_hi_hz;
  // Set under the progress lock by the thread whose callback threw: every other thread sees it
  // at its next report or order, however the threads are scheduled (the pool's own stop flag is
  // set only once the exception has left the worker).
  std::atomic<bool> cancelled{false};
  auto worker = [&](int tid, const std::atomic<bool>& stop) {
    while (!stop.load(std::memory_order_relaxed) && !cancelled.load()) {
      // Largest orders first: better load balance.
      const int idx = next.fetch_add(1);
      if (idx >= n_orders) break;
      const int p = order_max - idx;
      const double a0 = ThreadCpuSeconds();
      const Eigen::MatrixXd& M = reduced[p];
      const int na = m * p;
      Eigen::MatrixXd alpha(m * (p + 1), m);
      alpha.topRows(na) = -M.topLeftCorner(na, na).ldlt().solve(M.block(0, na, na, m));
      alpha.bottomRows(m).setIdentity();
      const double a1 = ThreadCpuSeconds();

      // Companion built from the TRANSPOSED coefficients: its eigenvectors then carry the left
      // null vectors of A(Omega), i.e. the participation factors (§2.7).
      Eigen::MatrixXd C = Eigen::MatrixXd::Zero(na, na);
      for (int j = 0; j + 1 < p; ++j) C.block(j * m, (j + 1) * m, m, m).setIdentity();
      for (int j = 0; j < p; ++j) C.block((p - 1) * m, j * m, m, m) = -alpha.block(j * m, 0, m, m).transpose();
      const Eigen::VectorXcd z = CompanionEigenvalues(C, m, p);
      std::vector<Pole> poles;
      // m = 1 vector test: shape B(Omega) = -(L^{-1} v)^T (Z alpha) with v = [1, Omega, .., Omega^p].
      Eigen::MatrixXd za;
      if (m == 1) {
        za.resize(p + 1, l);
        for (int c = 0; c <= p; ++c) za.row(c) = (zrows[c].leftCols(p + 1) * alpha.col(0)).transpose();
      }
      for (int k = 0; k < na; ++k) {
        const std::complex<double> om = z[k];
        if (!(om.imag() < 0.0) || std::abs(om) == 0.0) continue;  // Im(lambda) > 0 member only
        Pole pole;
        pole.order = p;
        pole.lambda_fitted = -std::log(om) / dt + std::complex<double>(0.0, map.alias_rad_s);
        pole.lambda = pole.lambda_fitted + data.window_decay_rate;
        PoleToFrequencyAndDamping(pole.lambda, &pole.frequency_hz, &pole.damping_ratio);
        pole.physical = pole.damping_ratio > 0.0 && pole.damping_ratio < options.damping_max &&
                        pole.frequency_hz >= band_lo && pole.frequency_hz <= band_hi;
        if (m >= 2) {
          Eigen::MatrixXcd a = Eigen::MatrixXcd::Zero(m, m);
          std::complex<double> zp = 1.0;
          for (int j = 0; j <= p; ++j, zp *= om) a += zp * alpha.block(j * m, 0, m, m).cast<std::complex<double>>();
          Eigen::JacobiSVD<Eigen::MatrixXcd> svd(a.transpose(), Eigen::ComputeFullV);
          pole.participation = svd.matrixV().col(m - 1);
        } else {
          pole.participation = Eigen::VectorXcd::Ones(1);
          if (pole.physical) {
            Eigen::VectorXcd v(p + 1);
            std::complex<double> zp = 1.0;
            for (int j = 0; j <= p; ++j, zp *= om) v[j] = zp;
            L.topLeftCorner(p + 1, p + 1).triangularView<Eigen::Lower>().solveInPlace(v);
            pole.shape = -(za.transpose().cast<std::complex<double>>() * v);
            const double nrm = pole.shape.norm();
            if (nrm > 0) pole.shape /= nrm;
          }
        }
        const double nrm = pole.participation.norm();
        if (nrm > 0) pole.participation /= nrm;
        poles.push_back(std::move(pole));
      }
      std::sort(poles.begin(), poles.end(), [](const Pole& a, const Pole& b) { return a.frequency_hz < b.frequency_hz; });
      diagram.orders[p - order_min] = std::move(poles);
      const double a2 = ThreadCpuSeconds();
      solve_time[tid] += a1 - a0;
      eig_time[tid] += a2 - a1;
      const int finished = ++done;
      if (progress) {
        std::lock_guard<std::mutex> lock(progress_mutex);
        if (cancelled.load()) break;
        try {
          progress(static_cast<double>(finished) / n_orders, "poles");
        } catch (...) {
          cancelled.store(true);
          throw;
        }
      }
    }
  };
  // A progress callback that throws (a cancellation) stops every worker at its next order and
  // reaches the caller.
  step();
  RunOnThreads(n_threads, worker);
  const auto t2 = Clock::now();
  if (timing) {
    timing->normal_equations = cpu1 - cpu0;
    timing->normal_equations_wall = Seconds(t0, t1);
    timing->solve_and_eigen_wall = Seconds(t1, t2);
    timing->solves = 0.0;
    timing->eigenvalues = 0.0;
    for (int t = 0; t < n_threads; ++t) {
      timing->solves += solve_time[t];
      timing->eigenvalues += eig_time[t];
    }
  }
  return diagram;
}

}  // namespace ema::curvefit
