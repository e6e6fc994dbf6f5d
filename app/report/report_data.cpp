// Data preparation of the HTML report: shape tables, the fit's modal model as FRFs, stabilisation points.
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

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

// "+Z", "Z", "-z" or a UFF code (3, -3).
int DirectionOf(const json& j) {
  if (j.is_number_integer()) return j.get<int>();
  if (j.is_string()) return ParseDirection(j.get<std::string>());
  return 0;
}

std::complex<double> ComplexOf(const json& j) {
  if (j.is_array() && j.size() == 2 && j[0].is_number() && j[1].is_number())
    return {j[0].get<double>(), j[1].get<double>()};
  if (j.is_number()) return {j.get<double>(), 0.0};
  return {kNaN, kNaN};
}

}  // namespace

ShapeTable ReadShapeTable(const json& modes_json) {
  ShapeTable table;
  if (!modes_json.is_object() || !modes_json.contains("modes") || !modes_json["modes"].is_array()) return table;
  const json& modes = modes_json["modes"];
  std::map<Dof, int> row;
  for (const json& mode : modes) {
    if (!mode.contains("shape") || !mode["shape"].is_array()) continue;
    for (const json& entry : mode["shape"]) {
      const int dir = DirectionOf(entry.value("dir", json()));
      if (!entry.contains("node") || !entry["node"].is_number_integer() || dir == 0) continue;
      const Dof dof{entry["node"].get<int>(), std::abs(dir)};
      if (!row.count(dof)) row.emplace(dof, 0);
    }
  }
  int next = 0;
  for (auto& [dof, index] : row) {
    index = next++;
    table.dofs.push_back(dof);
  }
  table.shapes = Eigen::MatrixXcd::Zero(static_cast<int>(table.dofs.size()), static_cast<int>(modes.size()));
  int column = 0;
  for (const json& mode : modes) {
    table.frequency_hz.push_back(Number(mode, "frequency_hz"));
    table.damping_ratio.push_back(Number(mode, "damping_ratio"));
    if (mode.contains("shape") && mode["shape"].is_array()) {
      for (const json& entry : mode["shape"]) {
        const int dir = DirectionOf(entry.value("dir", json()));
        if (!entry.contains("node") || !entry["node"].is_number_integer() || dir == 0) continue;
        const std::complex<double> value = ComplexOf(entry.value("value", json()));
        table.shapes(row.at(Dof{entry["node"].get<int>(), std::abs(dir)}), column) = dir < 0 ? -value : value;
      }
    }
    ++column;
  }
  return table;
}

Eigen::VectorXcd SynthesiseFromModalModel(const json& model, const Dof& response, const Dof& reference,
                                          const Eigen::VectorXd& frequency_hz) {
  const Eigen::Index n = frequency_hz.size();
  Eigen::VectorXcd out = Eigen::VectorXcd::Constant(n, {kNaN, kNaN});
  if (!model.is_object() || !model.contains("poles") || !model.contains("frfs") || !model["frfs"].is_array()) return out;
  const json* entry = nullptr;
  for (const json& frf : model["frfs"]) {
    if (!frf.is_object()) continue;
    const Dof res{frf.value("response_node", 0), DirectionOf(frf.value("response_dir", json()))};
    const Dof ref{frf.value("reference_node", 0), DirectionOf(frf.value("reference_dir", json()))};
    if (res == response && ref == reference) {
      entry = &frf;
      break;
    }
  }
  if (!entry || !entry->contains("residues") || !(*entry)["residues"].is_array()) return out;
  std::vector<std::complex<double>> poles, residues;
  for (const json& p : model["poles"]) poles.push_back(ComplexOf(p));
  for (const json& r : (*entry)["residues"]) residues.push_back(ComplexOf(r));
  if (poles.size() != residues.size()) return out;
  const std::string type = model.value("frf_type", std::string("accelerance"));
  const int k_pow = type == "receptance" ? 0 : type == "mobility" ? 1 : 2;
  const double lower = Number(*entry, "lower_residual", 0.0), upper = Number(*entry, "upper_residual", 0.0);
  double lo = 0.0, hi = std::numeric_limits<double>::infinity();
  if (model.contains("band_hz") && model["band_hz"].is_array() && model["band_hz"].size() == 2) {
    lo = model["band_hz"][0].get<double>();
    hi = model["band_hz"][1].get<double>();
  }
  for (Eigen::Index i = 0; i < n; ++i) {
    const double f = frequency_hz[i];
    if (!(f > 0.0) || f < lo || f > hi) continue;
    const std::complex<double> jw(0.0, kTwoPi * f);
    std::complex<double> v = lower / (jw * jw) + upper;
    for (size_t r = 0; r < poles.size(); ++r)
      v += residues[r] / (jw - poles[r]) + std::conj(residues[r]) / (jw - std::conj(poles[r]));
    out[i] = v * std::pow(jw, k_pow);
  }
  return out;
}

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
