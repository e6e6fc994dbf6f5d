// Interface laws in time about their operating point (docs/model.md "Laws in time").
#include "ema/model/law_force.hpp"

#include <algorithm>
#include <cmath>

#include "ema/core/error.hpp"
#include "interpolant.hpp"

namespace ema::model {
namespace {

using internal::MonotoneCubic;

constexpr int kSamples = 801;  // tabulated chain laws: 800 intervals over ±range

}  // namespace

LawForce::LawForce(const Law& law, const SpringState& operating, double range_m, double factor,
                   const std::string& where)
    : factor_(factor), stiffness_(operating.stiffness * factor) {
  if (!(range_m > 0.0) || !std::isfinite(range_m)) range_m = 1e-6;
  if (const auto* lin = std::get_if<LinearLaw>(&law.value)) {
    kind_ = Kind::kLinear;
    stiffness_ = lin->k * factor;
    return;
  }
  if (const auto* slip = std::get_if<MicroSlipLaw>(&law.value)) {
    kind_ = Kind::kMicroSlip;
    // Iwan: n elements of stiffness k/n slipping at u_max i/n (i = 1..n), slip forces summing
    // to slip_force: sum (k/n)(i/n) u_max = k u_max (n+1)/(2n) = slip_force.
    const int n = slip->elements;
    const double u_max = 2.0 * n * slip->slip_force / (slip->k * (n + 1));
    for (int i = 1; i <= n; ++i) {
      k_i_.push_back(slip->k / n);
      fs_i_.push_back(slip->k / n * u_max * i / n);
    }
    stiffness_ = slip->k * factor;
    Reset();
    return;
  }
  if (const auto* hertz = std::get_if<HertzLaw>(&law.value)) {
    kind_ = Kind::kHertz;
    hertz_c_ = 4.0 / 3.0 * hertz->modulus * std::sqrt(hertz->radius);
    pen0_ = std::max(0.0, operating.deflection - hertz->offset);
    f0_ = hertz_c_ * std::pow(pen0_, 1.5);
    return;
  }
  // Everything else: sample F(c) on a grid of compressions and interpolate linearly.
  kind_ = Kind::kCurve;
  std::vector<std::pair<double, double>> samples;
  if (const auto* table = std::get_if<TableLaw>(&law.value)) {
    const MonotoneCubic curve(table->deflection, table->force);
    for (int i = 0; i < kSamples; ++i) {
      const double c = -range_m + 2.0 * range_m * i / (kSamples - 1);
      samples.push_back({c, curve.ValueExtrapolated(operating.deflection + c) - operating.force});
    }
  } else if (const auto* film = std::get_if<AirFilmLaw>(&law.value)) {
    const MonotoneCubic w(film->gap, film->load);
    const double h0 = std::isnan(operating.gap) ? film->operating_gap : operating.gap;
    for (int i = 0; i < kSamples; ++i) {
      const double c = -range_m + 2.0 * range_m * i / (kSamples - 1);
      samples.push_back({c, w.ValueExtrapolated(h0 - c) - w.ValueExtrapolated(h0)});  // compression closes the gap
    }
  } else if (const auto* series = std::get_if<SeriesLaw>(&law.value)) {
    const bool film = std::any_of(series->elements.begin(), series->elements.end(),
                                  [](const Law& e) { return std::holds_alternative<AirFilmLaw>(e.value); });
    if (film) {
      // Compressing the chain by c moves its outer end in: the setting falls by c.
      const double setting = std::isnan(operating.gap) ? series->setting : operating.gap - operating.deflection;
      for (int i = 0; i < kSamples; ++i) {
        const double c = -range_m + 2.0 * range_m * i / (kSamples - 1);
        try {
          samples.push_back({c, LinearizeLaw(law, where, setting - c).force - operating.force});
        } catch (const InputError&) {
          // no equilibrium on the load-lift curve there: left to the linear extrapolation
        }
      }
    } else {
      // Chain force F -> total compression D(F); sample F until D covers d0 ± range.
      const double k0 = std::max(operating.stiffness, 1e-300);
      double span = k0 * range_m;
      if (!(span > 0.0)) span = 1.0;
      for (int grow = 0; grow < 60; ++grow) {
        const double d_hi = LinearizeLaw(law, where, operating.force + span).deflection;
        if (d_hi - operating.deflection >= range_m) break;
        span *= 2.0;
      }
      for (int i = 0; i < kSamples; ++i) {
        const double f = operating.force - span + 2.0 * span * i / (kSamples - 1);
        const double d = LinearizeLaw(law, where, f).deflection;
        if (samples.empty() || d - operating.deflection > samples.back().first)
          samples.push_back({d - operating.deflection, f - operating.force});
      }
    }
  } else {
    throw InputError(where, "law '" + law.KindName() + "' cannot be integrated in time");
  }
  if (samples.size() < 2)
    throw InputError(where, "law '" + law.KindName() + "': no force can be evaluated within ±" + std::to_string(range_m) +
                                " m of the operating point");
  for (const auto& [c, f] : samples) c_.push_back(c), f_.push_back(f);
  for (std::size_t i = 0; i + 1 < c_.size(); ++i) slope_.push_back((f_[i + 1] - f_[i]) / (c_[i + 1] - c_[i]));
}

double LawForce::Force(double c) const {
  switch (kind_) {
    case Kind::kLinear:
      return stiffness_ * c;
    case Kind::kHertz: {
      const double pen = pen0_ + c;
      return factor_ * ((pen > 0.0 ? hertz_c_ * std::pow(pen, 1.5) : 0.0) - f0_);
    }
    case Kind::kMicroSlip: {
      double f = 0.0;
      for (std::size_t i = 0; i < k_i_.size(); ++i)
        f += std::clamp(f_committed_[i] + k_i_[i] * (c - c_committed_), -fs_i_[i], fs_i_[i]);
      return factor_ * f;
    }
    case Kind::kCurve: {
      std::size_t i;
      if (c <= c_.front()) i = 0;
      else if (c >= c_.back()) i = slope_.size() - 1;
      else i = static_cast<std::size_t>(std::upper_bound(c_.begin(), c_.end(), c) - c_.begin()) - 1;
      i = std::min(i, slope_.size() - 1);
      return factor_ * (f_[i] + slope_[i] * (c - c_[i]));
    }
  }
  return 0.0;
}

void LawForce::Commit(double c) {
  if (kind_ != Kind::kMicroSlip) return;
  for (std::size_t i = 0; i < k_i_.size(); ++i)
    f_committed_[i] = std::clamp(f_committed_[i] + k_i_[i] * (c - c_committed_), -fs_i_[i], fs_i_[i]);
  c_committed_ = c;
}

void LawForce::Reset() {
  f_committed_.assign(k_i_.size(), 0.0);
  c_committed_ = 0.0;
}

}  // namespace ema::model
