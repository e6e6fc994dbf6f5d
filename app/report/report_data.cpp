// Data preparation of the HTML report: shape tables, MAC matrix, FRF synthesis, stabilisation points.
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
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

Eigen::MatrixXd MacMatrix(const ShapeTable& test, const ShapeTable& model, int* shared_dofs) {
  std::vector<std::pair<int, int>> shared;
  for (int i = 0; i < static_cast<int>(test.dofs.size()); ++i) {
    auto it = std::lower_bound(model.dofs.begin(), model.dofs.end(), test.dofs[i]);
    if (it != model.dofs.end() && *it == test.dofs[i]) shared.emplace_back(i, static_cast<int>(it - model.dofs.begin()));
  }
  if (shared_dofs) *shared_dofs = static_cast<int>(shared.size());
  if (shared.empty()) return {};
  const int n = static_cast<int>(shared.size());
  Eigen::MatrixXcd a(n, test.shapes.cols()), b(n, model.shapes.cols());
  for (int k = 0; k < n; ++k) {
    a.row(k) = test.shapes.row(shared[k].first);
    b.row(k) = model.shapes.row(shared[k].second);
  }
  Eigen::MatrixXd mac(a.cols(), b.cols());
  for (int i = 0; i < a.cols(); ++i) {
    for (int j = 0; j < b.cols(); ++j) {
      const double cross = std::norm(a.col(i).dot(b.col(j)));  // |a^H b|^2: complex-safe
      const double denominator = a.col(i).squaredNorm() * b.col(j).squaredNorm();
      mac(i, j) = denominator > 0.0 ? cross / denominator : 0.0;
    }
  }
  return mac;
}

Eigen::VectorXcd SynthesiseFrf(const Eigen::VectorXd& frequency_hz, const Eigen::VectorXcd& measured,
                               const std::vector<std::complex<double>>& poles, double lo_hz, double hi_hz) {
  const int n = static_cast<int>(frequency_hz.size());
  Eigen::VectorXcd out = Eigen::VectorXcd::Constant(n, {kNaN, kNaN});
  if (hi_hz <= lo_hz) {
    lo_hz = frequency_hz.size() ? frequency_hz.minCoeff() : 0.0;
    hi_hz = frequency_hz.size() ? frequency_hz.maxCoeff() : 0.0;
  }
  std::vector<int> lines;
  for (int i = 0; i < n; ++i)
    if (frequency_hz[i] >= lo_hz && frequency_hz[i] <= hi_hz && frequency_hz[i] > 0.0 && std::isfinite(std::abs(measured[i])))
      lines.push_back(i);
  const int columns = 2 * static_cast<int>(poles.size()) + 2;
  if (static_cast<int>(lines.size()) < columns + 1) return out;
  // Basis scaled by the band's top angular frequency so the columns are of similar size.
  const double scale = kTwoPi * hi_hz;
  auto basis = [&](double f_hz, int column) -> std::complex<double> {
    const std::complex<double> s(0.0, kTwoPi * f_hz / scale);
    const int k = column / 2;
    if (k < static_cast<int>(poles.size())) {
      const std::complex<double> pole = poles[k] / scale;
      return column % 2 == 0 ? 1.0 / (s - pole) : 1.0 / (s - std::conj(pole));
    }
    return column % 2 == 0 ? std::complex<double>(1.0, 0.0) : 1.0 / (s * s);
  };
  Eigen::MatrixXcd a(static_cast<int>(lines.size()), columns);
  Eigen::VectorXcd b(static_cast<int>(lines.size()));
  for (int r = 0; r < static_cast<int>(lines.size()); ++r) {
    for (int c = 0; c < columns; ++c) a(r, c) = basis(frequency_hz[lines[r]], c);
    b[r] = measured[lines[r]];
  }
  const Eigen::VectorXcd x = a.colPivHouseholderQr().solve(b);
  for (int i : lines) {
    std::complex<double> value = 0.0;
    for (int c = 0; c < columns; ++c) value += x[c] * basis(frequency_hz[i], c);
    out[i] = value;
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
