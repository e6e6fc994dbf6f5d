#include "ema/curvefit/peak.hpp"

#include <cmath>

#include "ema/curvefit/complexity.hpp"
#include "ema/curvefit/lsfd.hpp"

namespace ema::curvefit {

ModeSet PeakPick(const FitData& data, const PeakOptions& options) {
  const int n = data.LineCount(), l = data.OutputCount(), m = data.ReferenceCount();
  Eigen::VectorXd s = Eigen::VectorXd::Zero(n);
  for (int o = 0; o < l; ++o)
    for (int i = 0; i < m; ++i) s += data.h.col(o * m + i).cwiseAbs() * data.output_weight[o];
  ModeSet set;
  set.dofs = data.outputs;
  auto valid = [&](int k) { return data.line_weight[k] > 0.0; };
  for (int k = 1; k + 1 < n; ++k) {
    if (!valid(k) || !valid(k - 1) || !valid(k + 1) || !(s[k] > s[k - 1] && s[k] >= s[k + 1])) continue;
    // Valleys: walk down each side until the curve rises above the peak or the band ends.
    double left_min = s[k], right_min = s[k];
    for (int j = k - 1; j >= 0 && s[j] <= s[k]; --j) left_min = std::min(left_min, s[j]);
    for (int j = k + 1; j < n && s[j] <= s[k]; ++j) right_min = std::min(right_min, s[j]);
    if (s[k] < options.prominence * std::max(left_min, right_min)) continue;
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
    if (!std::isfinite(fa) || !std::isfinite(fb)) continue;
    // Peak frequency refined by a parabola through the three top lines.
    const double den = s[k - 1] - 2.0 * s[k] + s[k + 1];
    const double shift = den != 0.0 ? 0.5 * (s[k - 1] - s[k + 1]) / den : 0.0;
    const double fr = data.frequency_hz[k] + shift * data.line_spacing_hz;
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
