#include "ema/curvefit/complexity.hpp"

#include <cstdio>

#include "ema/core/error.hpp"
#include "ema/curvefit/lsfd.hpp"

namespace ema::curvefit {

double ModeComplexityFactor(const Eigen::VectorXcd& shape) {
  const Eigen::VectorXd x = shape.real(), y = shape.imag();
  const double sxx = x.squaredNorm(), syy = y.squaredNorm(), sxy = x.dot(y);
  const double den = (sxx + syy) * (sxx + syy);
  if (!(den > 0.0)) return kNaN;
  return std::max(0.0, 1.0 - ((sxx - syy) * (sxx - syy) + 4.0 * sxy * sxy) / den);
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
