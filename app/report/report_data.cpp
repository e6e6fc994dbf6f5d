// Data preparation of the HTML report: the stabilisation points of `ema fit --stabilisation`.
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "report.hpp"

namespace ema::report {

namespace {

using json = nlohmann::json;

double Number(const json& j, const char* key, double fallback = kNaN) {
  if (!j.is_object()) return fallback;
  auto it = j.find(key);
  if (it == j.end() || !it->is_number()) return fallback;
  return it->get<double>();
}

std::complex<double> ComplexOf(const json& j) {
  if (j.is_array() && j.size() == 2 && j[0].is_number() && j[1].is_number())
    return {j[0].get<double>(), j[1].get<double>()};
  if (j.is_number()) return {j.get<double>(), 0.0};
  return {kNaN, kNaN};
}

}  // namespace

StabilisationPoints ReadStabilisation(const json& stabilisation) {
  StabilisationPoints points;
  auto add_pole = [&](const json& pole, int order) {
    if (!pole.is_object()) return;
    double f = Number(pole, "frequency_hz");
    double zeta = Number(pole, "damping_ratio");
    if (!std::isfinite(f) && pole.contains("pole")) {
      const std::complex<double> lambda = ComplexOf(pole["pole"]);
      PoleToFrequencyAndDamping(lambda, &f, &zeta);
    }
    if (!std::isfinite(f)) return;
    const int pole_order = pole.contains("order") && pole["order"].is_number() ? pole["order"].get<int>() : order;
    std::string status;
    if (pole.contains("label") && pole["label"].is_string()) {
      // ema fit's letters: s = stable in frequency, damping and vector; f, d, v = partly; o = new.
      const std::string label = pole["label"].get<std::string>();
      status = label == "s" ? "stable" : label == "o" ? "unstable" : label;
    } else if (pole.contains("status") && pole["status"].is_string()) {
      status = pole["status"].get<std::string>();
    } else if (pole.contains("stable") && pole["stable"].is_boolean()) {
      status = pole["stable"].get<bool>() ? "stable" : "unstable";
    } else {
      // Per-criterion flags: stable only when every criterion given holds.
      bool any = false, all = true;
      for (const char* key : {"stable_frequency", "stable_damping", "stable_vector", "stable_mac"}) {
        if (pole.contains(key) && pole[key].is_boolean()) {
          any = true;
          all = all && pole[key].get<bool>();
        }
      }
      status = any && all ? "stable" : "unstable";
    }
    if (pole.contains("physical") && pole["physical"].is_boolean() && !pole["physical"].get<bool>())
      status = "non-physical";
    points.order.push_back(pole_order);
    points.frequency_hz.push_back(f);
    points.damping_ratio.push_back(zeta);
    points.status.push_back(status);
  };
  if (!stabilisation.is_object()) return points;
  if (stabilisation.contains("orders") && stabilisation["orders"].is_array()) {
    for (const json& level : stabilisation["orders"]) {
      const int order = level.is_object() && level.contains("order") && level["order"].is_number() ? level["order"].get<int>() : 0;
      if (level.is_object() && level.contains("poles") && level["poles"].is_array())
        for (const json& pole : level["poles"]) add_pole(pole, order);
    }
  } else if (stabilisation.contains("poles") && stabilisation["poles"].is_array()) {
    for (const json& pole : stabilisation["poles"]) add_pole(pole, 0);
  }
  return points;
}

}  // namespace ema::report
