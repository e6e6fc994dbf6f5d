#include "ema/curvefit/peak.hpp"

#include <Eigen/Dense>
#include <cmath>

#include "ema/curvefit/complexity.hpp"
#include "ema/curvefit/lsfd.hpp"

namespace ema::curvefit {

ModeSet PeakPick(const FitData& data, const PeakOptions& options) {
  const int n = data.LineCount(), l = data.OutputCount(), m = data.ReferenceCount();
  Eigen::VectorXd s = Eigen::VectorXd::Zero(n);
  for (int o = 0; o < l; ++o)
    // |H| as sqrt(re² + im²), vectorised: hypot's overflow guard is not needed for FRF values
    // and costs a tenth of a large file's whole fit.
    for (int i = 0; i < m; ++i) s += data.h.col(o * m + i).cwiseAbs2().cwiseSqrt() * data.output_weight[o];
  ModeSet set;
  set.dofs = data.outputs;
  auto valid = [&](int k) { return data.line_weight[k] > 0.0; };
  for (int k = 1; k + 1 < n; ++k) {
    if (!valid(k) || !valid(k - 1) || !valid(k + 1) || !(s[k] > s[k - 1] && s[k] >= s[k + 1])) continue;
    // Valleys: walk down each side until the curve rises above the peak or the band ends. A
    // side that reaches the band edge is open: a narrow band around one mode cuts its valleys
    // off, so an open side only counts when both are open (then the lower one).
    double left_min = s[k], right_min = s[k];
    int jl = k - 1, jr = k + 1;
    for (; jl >= 0 && s[jl] <= s[k]; --jl) left_min = std::min(left_min, s[jl]);
    for (; jr < n && s[jr] <= s[k]; ++jr) right_min = std::min(right_min, s[jr]);
    const bool left_open = jl < 0, right_open = jr >= n;
    const double valley = left_open && right_open ? std::min(left_min, right_min)
                          : left_open             ? right_min
                          : right_open            ? left_min
                                                  : std::max(left_min, right_min);
    if (s[k] < options.prominence * valley) continue;
    // Half-power crossings by linear interpolation between lines.
    const double half = s[k] / std::sqrt(2.0);
    double fb = kNaN, fa = kNaN;
    for (int j = k; j > 0; --j)
      if (s[j - 1] < half) {
        fb = data.frequency_hz[j - 1] + (half - s[j - 1]) / (s[j] - s[j - 1]) * data.line_spacing_hz;
        break;
      }
    for (int j = k; j + 1 < n; ++j)
      if (s[j + 1] < half) {
        fa = data.frequency_hz[j] + (s[j] - half) / (s[j] - s[j + 1]) * data.line_spacing_hz;
        break;
      }
    if (!std::isfinite(fa) && !std::isfinite(fb)) continue;
    // Peak frequency: near a resonance 1/|H|^2 is a parabola in f with its vertex at the
    // resonance, so fit one by least squares to every line above the half-power level (at least
    // the three top lines); a broad, noisy peak then uses all its lines, not just three.
    double fr = data.frequency_hz[k];
    {
      int lo = k - 1, hi = k + 1;
      while (lo > 0 && valid(lo - 1) && s[lo - 1] >= half) --lo;
      while (hi + 1 < n && valid(hi + 1) && s[hi + 1] >= half) ++hi;
      Eigen::Matrix3d ata = Eigen::Matrix3d::Zero();
      Eigen::Vector3d atb = Eigen::Vector3d::Zero();
      for (int j = lo; j <= hi; ++j) {
        const double x = (data.frequency_hz[j] - data.frequency_hz[k]) / data.line_spacing_hz;
        const Eigen::Vector3d row(1.0, x, x * x);
        const double g = 1.0 / (s[j] * s[j]), w = s[j] * s[j] * s[j] * s[j];  // relative errors of g alike
        ata += w * row * row.transpose();
        atb += w * row * g;
      }
      const Eigen::Vector3d c = ata.ldlt().solve(atb);
      const double shift = c[2] > 0.0 ? -c[1] / (2.0 * c[2]) : 0.0;
      if (std::isfinite(shift) && std::abs(shift) <= 1.0) {
        fr += shift * data.line_spacing_hz;
      } else {
        const double den = s[k - 1] - 2.0 * s[k] + s[k + 1];
        fr += (den != 0.0 ? 0.5 * (s[k - 1] - s[k + 1]) / den : 0.0) * data.line_spacing_hz;
      }
    }
    // A half-power point beyond the band edge: mirror the other one about the peak.
    if (!std::isfinite(fa)) fa = 2.0 * fr - fb;
    if (!std::isfinite(fb)) fb = 2.0 * fr - fa;
    const double eta = (fa * fa - fb * fb) / (2.0 * fr * fr);  // Eq. 4.44
    Mode mode;
    const std::complex<double> measured = FrequencyAndDampingToPole(fr, eta / 2.0);  // Eq. 4.45
    mode.pole = measured + data.window_decay_rate;
    PoleToFrequencyAndDamping(mode.pole, &mode.frequency_hz, &mode.damping_ratio);
    int best_ref = 0;
    double best = -1.0;
    for (int i = 0; i < m; ++i) {
      double e = 0.0;
      for (int o = 0; o < l; ++o) e += std::abs(data.H(k, o, i)) * data.output_weight[o];
      if (e > best) best = e, best_ref = i;
    }
    mode.shape.resize(l);
    for (int o = 0; o < l; ++o) mode.shape[o] = data.H(k, o, best_ref);
    int omax = 0;
    mode.shape.cwiseAbs().maxCoeff(&omax);
    if (std::abs(mode.shape[omax]) > 0.0) mode.shape /= mode.shape[omax];
    mode.mpc = ModalPhaseCollinearity(mode.shape);
    mode.mpd = MeanPhaseDeviationDeg(mode.shape);
    mode.mcf = ModeComplexityFactor(mode.shape);
    set.modes.push_back(std::move(mode));
  }
  return set;
}

}  // namespace ema::curvefit
