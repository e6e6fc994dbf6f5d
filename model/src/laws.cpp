// Operating points and linearised stiffness of every interface law (model-format.md "Laws").
#include "ema/model/laws.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <sstream>

#include "ema/core/error.hpp"
#include "interpolant.hpp"

namespace ema::model {
namespace {

using internal::MonotoneCubic;

std::string Num(double v) {
  std::ostringstream s;
  s.precision(6);
  s << v;
  return s.str();
}

void CheckCurve(const std::vector<double>& x, const std::vector<double>& y, const char* x_name, const char* y_name,
                bool y_increasing, const std::string& where) {
  if (x.size() != y.size())
    throw InputError(where, std::string(x_name) + " has " + std::to_string(x.size()) + " values but " + y_name +
                                " has " + std::to_string(y.size()));
  if (x.size() < 2) throw InputError(where, std::string(x_name) + " needs at least 2 values");
  for (std::size_t i = 0; i < x.size(); ++i) {
    if (!std::isfinite(x[i]) || !std::isfinite(y[i]))
      throw InputError(where, std::string("non-finite value at index ") + std::to_string(i));
    if (i == 0) continue;
    if (!(x[i] > x[i - 1]))
      throw InputError(where, std::string(x_name) + " must increase strictly: " + x_name + "[" + std::to_string(i) +
                                  "] = " + Num(x[i]) + " after " + Num(x[i - 1]));
    const bool ok = y_increasing ? y[i] > y[i - 1] : y[i] < y[i - 1];
    if (!ok)
      throw InputError(where, std::string("non-monotone curve: ") + y_name + " must " +
                                  (y_increasing ? "increase" : "decrease") + " strictly with " + x_name + ", but " +
                                  y_name + "[" + std::to_string(i) + "] = " + Num(y[i]) + " after " + Num(y[i - 1]));
  }
}

void CheckMicroSlip(const MicroSlipLaw& law, const std::string& where) {
  if (!(law.k > 0.0) || !std::isfinite(law.k)) throw InputError(where, "micro_slip law needs k > 0, got " + Num(law.k));
  if (!(law.slip_force > 0.0) || !std::isfinite(law.slip_force))
    throw InputError(where, "micro_slip law needs slip_force > 0, got " + Num(law.slip_force));
  if (law.elements < 1 || law.elements > 1000)
    throw InputError(where, "micro_slip law needs elements in 1..1000, got " + std::to_string(law.elements));
}

struct ElementResponse {
  double deflection = 0.0;
  double stiffness = 0.0;
};

/// Compression and tangent stiffness of a chain element carrying force f (no air film).
ElementResponse ElementAtForce(const Law& law, double f, const std::string& where) {
  if (const auto* lin = std::get_if<LinearLaw>(&law.value)) {
    if (!(lin->k > 0.0)) throw InputError(where, "linear law needs k > 0 inside a series chain, got " + Num(lin->k));
    return {f / lin->k, lin->k};
  }
  if (const auto* table = std::get_if<TableLaw>(&law.value)) {
    CheckCurve(table->deflection, table->force, "deflection", "force", true, where);
    MonotoneCubic c(table->deflection, table->force);
    const double d = c.Inverse(f);
    return {d, c.Slope(std::clamp(d, c.XMin(), c.XMax()))};
  }
  if (const auto* hertz = std::get_if<HertzLaw>(&law.value)) {
    if (!(hertz->modulus > 0.0) || !(hertz->radius > 0.0))
      throw InputError(where, "hertz law needs modulus > 0 and radius > 0");
    if (f <= 0.0) return {hertz->offset, 0.0};
    const double c = 4.0 / 3.0 * hertz->modulus * std::sqrt(hertz->radius);
    const double pen = std::pow(f / c, 2.0 / 3.0);
    return {hertz->offset + pen, 2.0 * hertz->modulus * std::sqrt(hertz->radius * pen)};
  }
  if (const auto* series = std::get_if<SeriesLaw>(&law.value)) {
    ElementResponse sum;
    double compliance = 0.0;
    for (const Law& e : series->elements) {
      const ElementResponse r = ElementAtForce(e, f, where);
      sum.deflection += r.deflection;
      compliance += r.stiffness > 0.0 ? 1.0 / r.stiffness : INFINITY;
    }
    sum.stiffness = std::isfinite(compliance) && compliance > 0.0 ? 1.0 / compliance : 0.0;
    return sum;
  }
  if (std::holds_alternative<MicroSlipLaw>(law.value))
    throw InputError(where, "a micro_slip law cannot sit inside a series chain (it is hysteretic); give it its own spring");
  throw InputError(where, "a series chain may hold one air_film only, and not inside a nested series");
}

SpringState SolveAirFilmChain(const SeriesLaw& series, std::size_t film_index, double setting,
                              const std::string& where) {
  const auto& film = std::get<AirFilmLaw>(series.elements[film_index].value);
  CheckCurve(film.gap, film.load, "gap", "load", false, where);
  const MonotoneCubic w(film.gap, film.load);
  auto compressions = [&](double load) {
    double d = 0.0;
    for (std::size_t i = 0; i < series.elements.size(); ++i)
      if (i != film_index) d += ElementAtForce(series.elements[i], load, where).deflection;
    return d;
  };
  // g(h) = h - setting - sum d_i(W(h)) increases with h (W falls, d_i rise with force).
  auto g = [&](double h) { return h - setting - compressions(w.Value(h)); };
  double lo = w.XMin(), hi = w.XMax();
  const double g_lo = g(lo), g_hi = g(hi);
  if (g_lo > 0.0)
    throw InputError(where, "series chain has no equilibrium in range: at the smallest gap of the load-lift curve (" +
                                Num(lo) + " m) setting + compressions = " + Num(lo - g_lo) +
                                " m already exceeds it (setting " + Num(setting) + " m too small?)");
  if (g_hi < 0.0)
    throw InputError(where, "series chain has no equilibrium in range: at the largest gap of the load-lift curve (" +
                                Num(hi) + " m) setting + compressions = " + Num(hi - g_hi) +
                                " m is still larger (setting " + Num(setting) + " m too large?)");
  for (int iter = 0; iter < 200 && hi - lo > 1e-14 * hi; ++iter) {
    const double mid = 0.5 * (lo + hi);
    if (g(mid) < 0.0) lo = mid; else hi = mid;
  }
  const double h = 0.5 * (lo + hi);
  const double load = w.Value(h);
  SpringState s;
  s.law = "series";
  s.gap = h;
  s.force = load;
  double compliance = 0.0;
  for (std::size_t i = 0; i < series.elements.size(); ++i) {
    ElementResponse r;
    if (i == film_index) {
      r.deflection = h;  // the air-film element reports its gap
      r.stiffness = -w.Slope(h);
    } else {
      r = ElementAtForce(series.elements[i], load, where);
      s.deflection += r.deflection;
    }
    s.element_deflections.push_back(r.deflection);
    s.element_stiffnesses.push_back(r.stiffness);
    compliance += r.stiffness > 0.0 ? 1.0 / r.stiffness : INFINITY;
  }
  // Table elements extrapolate during the search; the equilibrium itself must lie on the table.
  for (std::size_t i = 0; i < series.elements.size(); ++i)
    if (const auto* t = std::get_if<TableLaw>(&series.elements[i].value))
      if (load < t->force.front() || load > t->force.back())
        throw InputError(where, "series chain equilibrium force " + Num(load) + " N lies outside element " +
                                    std::to_string(i + 1) + "'s table force range [" + Num(t->force.front()) + ", " +
                                    Num(t->force.back()) + "]");
  s.stiffness = std::isfinite(compliance) && compliance > 0.0 ? 1.0 / compliance : 0.0;
  return s;
}

/// What fixes the operating point of a law given by deflection or by force: the force when the law
/// names a force and no deflection, else the deflection; an override (not NaN) replaces the
/// value. Throws InputError(where, missing) when neither the law nor the override gives one.
struct OperatingInput {
  bool by_force = false;
  double value = 0.0;
};

OperatingInput OperatingInputOf(const std::optional<double>& deflection, const std::optional<double>& force,
                                double override_value, const std::string& where, const char* missing) {
  const bool has_override = !std::isnan(override_value);
  if (!has_override && !deflection && !force) throw InputError(where, missing);
  OperatingInput op;
  op.by_force = !deflection && force;
  op.value = has_override ? override_value : op.by_force ? *force : *deflection;
  return op;
}

}  // namespace

SpringState LinearizeLaw(const Law& law, const std::string& where, double override_value) {
  const bool has_override = !std::isnan(override_value);
  SpringState s;
  s.law = law.KindName();
  if (const auto* lin = std::get_if<LinearLaw>(&law.value)) {
    if (!std::isfinite(lin->k) || lin->k < 0.0) throw InputError(where, "linear law needs k >= 0, got " + Num(lin->k));
    s.stiffness = lin->k;
    return s;
  }
  if (const auto* table = std::get_if<TableLaw>(&law.value)) {
    CheckCurve(table->deflection, table->force, "deflection", "force", true, where);
    MonotoneCubic c(table->deflection, table->force);
    const OperatingInput op = OperatingInputOf(table->operating_deflection, table->operating_force, override_value,
                                               where, "table law needs an operating `deflection` or `force`");
    double d = 0.0;
    if (op.by_force) {
      const double f = op.value;
      if (f < c.YFirst() || f > c.YLast())
        throw InputError(where, "operating force " + Num(f) + " N outside the table [" + Num(c.YFirst()) + ", " +
                                    Num(c.YLast()) + "]");
      d = c.Inverse(f);
    } else {
      d = op.value;
      if (d < c.XMin() || d > c.XMax())
        throw InputError(where, "operating deflection " + Num(d) + " m outside the table [" + Num(c.XMin()) + ", " +
                                    Num(c.XMax()) + "]");
    }
    s.deflection = d;
    s.force = c.Value(d);
    s.stiffness = c.Slope(d);
    return s;
  }
  if (const auto* film = std::get_if<AirFilmLaw>(&law.value)) {
    CheckCurve(film->gap, film->load, "gap", "load", false, where);
    MonotoneCubic w(film->gap, film->load);
    const double h = has_override ? override_value : film->operating_gap;
    if (h < w.XMin() || h > w.XMax())
      throw InputError(where, "operating gap " + Num(h) + " m outside the load-lift curve [" + Num(w.XMin()) + ", " +
                                  Num(w.XMax()) + "]");
    s.gap = h;
    s.force = w.Value(h);
    s.stiffness = -w.Slope(h);
    return s;
  }
  if (const auto* hertz = std::get_if<HertzLaw>(&law.value)) {
    if (!(hertz->modulus > 0.0) || !(hertz->radius > 0.0))
      throw InputError(where, "hertz law needs modulus > 0 and radius > 0");
    const double c = 4.0 / 3.0 * hertz->modulus * std::sqrt(hertz->radius);
    const OperatingInput op = OperatingInputOf(hertz->operating_deflection, hertz->operating_force, override_value,
                                               where, "hertz law needs an operating `deflection` or `force` (preload)");
    double pen = 0.0;
    if (op.by_force) {
      pen = op.value > 0.0 ? std::pow(op.value / c, 2.0 / 3.0) : 0.0;
    } else {
      pen = std::max(0.0, op.value - hertz->offset);
    }
    s.deflection = hertz->offset + pen;
    s.force = c * std::pow(pen, 1.5);
    s.stiffness = 2.0 * hertz->modulus * std::sqrt(hertz->radius * pen);
    return s;
  }
  if (const auto* slip = std::get_if<MicroSlipLaw>(&law.value)) {
    CheckMicroSlip(*slip, where);
    s.stiffness = slip->k;  // stuck: linear until the first element slips
    return s;
  }
  const auto& series = std::get<SeriesLaw>(law.value);
  if (series.elements.empty()) throw InputError(where, "series law needs at least one element");
  std::size_t films = 0, film_index = 0;
  for (std::size_t i = 0; i < series.elements.size(); ++i)
    if (std::holds_alternative<AirFilmLaw>(series.elements[i].value)) ++films, film_index = i;
  if (films > 1) throw InputError(where, "series chain holds " + std::to_string(films) + " air_film elements; one allowed");
  if (films == 1) {
    const double setting = has_override ? override_value : series.setting;
    s = SolveAirFilmChain(series, film_index, setting, where);
    return s;
  }
  // No air film: every element carries the chain force, or (no force given) its own operating
  // point.
  const std::optional<double> force = has_override ? std::optional<double>(override_value) : series.force;
  double compliance = 0.0;
  for (const Law& e : series.elements) {
    SpringState es;
    if (force) {
      const ElementResponse r = ElementAtForce(e, *force, where);
      es.deflection = r.deflection;
      es.stiffness = r.stiffness;
      s.force = *force;
    } else {
      es = LinearizeLaw(e, where);
    }
    s.deflection += es.deflection;
    s.element_deflections.push_back(es.deflection);
    s.element_stiffnesses.push_back(es.stiffness);
    compliance += es.stiffness > 0.0 ? 1.0 / es.stiffness : INFINITY;
  }
  s.stiffness = std::isfinite(compliance) && compliance > 0.0 ? 1.0 / compliance : 0.0;
  return s;
}

}  // namespace ema::model
