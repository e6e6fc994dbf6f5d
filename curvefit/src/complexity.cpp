#include "ema/curvefit/complexity.hpp"

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "ema/core/error.hpp"

namespace ema::curvefit {

double ModalPhaseCollinearity(const Eigen::VectorXcd& shape) {
  const Eigen::VectorXd x = shape.real(), y = shape.imag();
  const double sxx = x.squaredNorm(), syy = y.squaredNorm(), sxy = x.dot(y);
  const double den = (sxx + syy) * (sxx + syy);
  return den > 0.0 ? ((sxx - syy) * (sxx - syy) + 4.0 * sxy * sxy) / den : kNaN;
}

double MeanPhaseDeviationDeg(const Eigen::VectorXcd& shape) {
  const int n = static_cast<int>(shape.size());
  if (n == 0) return kNaN;
  Eigen::MatrixXd ri(n, 2);
  ri.col(0) = shape.real();
  ri.col(1) = shape.imag();
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(ri, Eigen::ComputeFullV);
  const double vx = svd.matrixV()(0, 0), vy = svd.matrixV()(1, 0);
  double num = 0.0, den = 0.0;
  for (int i = 0; i < n; ++i) {
    const double a = std::abs(shape[i]);
    if (a == 0.0) continue;
    const double c = std::min(1.0, std::abs(shape[i].real() * vx + shape[i].imag() * vy) / a);
    num += a * std::acos(c);
    den += a;
  }
  return den > 0.0 ? num / den * 180.0 / M_PI : kNaN;
}

double ModeComplexityFactor(const Eigen::VectorXcd& shape) {
  const double mpc = ModalPhaseCollinearity(shape);
  return std::isnan(mpc) ? kNaN : std::max(0.0, 1.0 - mpc);
}

bool ComplexityOptions::IsValid(std::string* error) const {
  if (!(mpc_min >= 0.0 && mpc_min <= 1.0)) {
    if (error) *error = "mpc_min must be in [0, 1]";
    return false;
  }
  if (!(mpd_max_deg > 0.0 && mpd_max_deg <= 90.0)) {
    if (error) *error = "mpd_max_deg must be in (0, 90]";
    return false;
  }
  return true;
}

std::vector<ModeComplexityCheck> CheckModeComplexity(const ModeSet& modes, const ComplexityOptions& options) {
  std::string error;
  if (!options.IsValid(&error)) throw InputError("complexity options", error);
  std::vector<ModeComplexityCheck> out;
  for (size_t r = 0; r < modes.modes.size(); ++r) {
    const Mode& m = modes.modes[r];
    ModeComplexityCheck c;
    c.index = static_cast<int>(r);
    c.frequency_hz = m.frequency_hz;
    c.mpc = ModalPhaseCollinearity(m.shape);
    c.mpd_deg = MeanPhaseDeviationDeg(m.shape);
    c.mcf = ModeComplexityFactor(m.shape);
    char buf[200];
    std::snprintf(buf, sizeof buf, "mode %d (%.2f Hz): MPC %.3f, MPD %.1f deg, MCF %.3f", c.index + 1, c.frequency_hz,
                  c.mpc, c.mpd_deg, c.mcf);
    c.reason = buf;
    if (!(c.mpc >= options.mpc_min) || !(c.mpd_deg <= options.mpd_max_deg)) {
      c.verdict = frf::Verdict::kWarn;
      std::snprintf(buf, sizeof buf, " (MPC < %.2f or MPD > %.0f deg): complex mode; check for close modes, "
                    "non-proportional damping or a poorly fitted pole", options.mpc_min, options.mpd_max_deg);
      c.reason += buf;
    }
    out.push_back(c);
  }
  return out;
}

}  // namespace ema::curvefit
