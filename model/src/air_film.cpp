#include "ema/model/air_film.hpp"

#include <cmath>
#include <numbers>

#include "ema/core/error.hpp"

namespace ema::model {
namespace {

void Check(const PorousPad& pad) {
  if (!(pad.diameter > 0 && pad.thickness > 0 && pad.permeability > 0 && pad.supply_pressure > 0 &&
        pad.ambient_pressure > 0 && pad.gap_min > 0 && pad.gap_max > pad.gap_min && pad.points >= 4))
    throw InputError("", "air_film pad: diameter, thickness, permeability, supply_pressure, ambient_pressure must be > 0, "
                         "0 < gap_min < gap_max and points >= 4");
}

}  // namespace

double PorousPadLoad(const PorousPad& pad, double gap) {
  Check(pad);
  if (!(gap > 0)) throw InputError("", "air_film pad: gap must be > 0");
  const double radius = 0.5 * pad.diameter;
  const double pa = pad.ambient_pressure, ps = pad.supply_pressure + pa;
  const double lambda = std::sqrt(12.0 * pad.permeability / (pad.thickness * gap * gap * gap));
  // I0(L r)/I0(L R); for large arguments the asymptotic I0(x) ~ e^x / sqrt(2 pi x) avoids overflow.
  const double lr = lambda * radius;
  auto ratio = [&](double r) {
    const double x = lambda * r;
    if (lr < 500.0) return std::cyl_bessel_i(0.0, x) / std::cyl_bessel_i(0.0, lr);
    if (x < 1.0) return 0.0;
    return std::exp(x - lr) * std::sqrt(lr / x);
  };
  // Composite Simpson over r; the integrand is smooth (p rises from Pa at the rim).
  constexpr int kIntervals = 400;
  double sum = 0.0;
  for (int i = 0; i <= kIntervals; ++i) {
    const double r = radius * i / kIntervals;
    const double p2 = ps * ps - (ps * ps - pa * pa) * ratio(r);
    const double f = (std::sqrt(std::max(p2, pa * pa)) - pa) * r;
    sum += f * (i == 0 || i == kIntervals ? 1.0 : (i % 2 ? 4.0 : 2.0));
  }
  return 2.0 * std::numbers::pi * sum * radius / kIntervals / 3.0;
}

AirFilmLaw PorousPadCurve(const PorousPad& pad, double operating_gap) {
  Check(pad);
  AirFilmLaw law;
  law.operating_gap = operating_gap;
  for (int i = 0; i < pad.points; ++i) {
    const double h = pad.gap_min * std::pow(pad.gap_max / pad.gap_min, static_cast<double>(i) / (pad.points - 1));
    law.gap.push_back(h);
    law.load.push_back(PorousPadLoad(pad, h));
  }
  return law;
}

}  // namespace ema::model
