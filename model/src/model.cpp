// Small helpers of the model value types.
#include "ema/model/model.hpp"

#include <Eigen/SparseCholesky>

#include <algorithm>

namespace ema::model {

std::string Law::KindName() const {
  static const char* kNames[] = {"linear", "table", "air_film", "hertz", "series", "micro_slip"};
  return kNames[value.index()];
}

bool Law::IsNonlinear() const {
  if (std::holds_alternative<LinearLaw>(value) || std::holds_alternative<MicroSlipLaw>(value)) return false;
  if (const auto* series = std::get_if<SeriesLaw>(&value)) {
    return std::any_of(series->elements.begin(), series->elements.end(),
                       [](const Law& e) { return e.IsNonlinear(); });
  }
  return true;
}

bool Law::IsNonlinearInTime() const {
  if (std::holds_alternative<LinearLaw>(value)) return false;
  if (const auto* series = std::get_if<SeriesLaw>(&value)) {
    return std::any_of(series->elements.begin(), series->elements.end(),
                       [](const Law& e) { return e.IsNonlinearInTime(); });
  }
  return true;
}

double Damping::RatioOfMode(int elastic_mode_index) const {
  if (ratios.empty()) return ratio;
  const auto i = std::min<std::size_t>(static_cast<std::size_t>(std::max(0, elastic_mode_index)), ratios.size() - 1);
  return ratios[i];
}

const Body* Model::FindBody(const std::string& body_name) const {
  for (const Body& b : bodies)
    if (b.name == body_name) return &b;
  return nullptr;
}

Body* Model::FindBody(const std::string& body_name) {
  for (Body& b : bodies)
    if (b.name == body_name) return &b;
  return nullptr;
}

std::string Model::Where(int line) const {
  const std::string file = origin.empty() ? std::string("model") : origin;
  return line > 0 ? file + ":" + std::to_string(line) : file;
}

int FirstNegativePivotRow(const Eigen::SparseMatrix<double>& a) {
  std::vector<int> used(static_cast<std::size_t>(a.rows()), -1), rows;
  for (int c = 0; c < a.outerSize(); ++c)
    for (Eigen::SparseMatrix<double>::InnerIterator it(a, c); it; ++it)
      if (it.value() != 0.0 && used[static_cast<std::size_t>(it.row())] < 0) {
        used[static_cast<std::size_t>(it.row())] = static_cast<int>(rows.size());
        rows.push_back(static_cast<int>(it.row()));
      }
  if (rows.empty()) return -1;
  std::vector<Eigen::Triplet<double>> entries;
  double largest = 0.0;
  for (int c = 0; c < a.outerSize(); ++c)
    for (Eigen::SparseMatrix<double>::InnerIterator it(a, c); it; ++it) {
      const int r = used[static_cast<std::size_t>(it.row())], k = used[static_cast<std::size_t>(it.col())];
      if (r < 0 || k < 0) continue;
      entries.emplace_back(r, k, it.value());
      if (r == k) largest = std::max(largest, std::abs(it.value()));
    }
  const auto n = static_cast<Eigen::Index>(rows.size());
  for (Eigen::Index i = 0; i < n; ++i) entries.emplace_back(i, i, 1e-9 * largest);
  Eigen::SparseMatrix<double> sub(n, n);
  sub.setFromTriplets(entries.begin(), entries.end());
  const Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(sub);
  if (ldlt.info() != Eigen::Success) return rows[0];
  const Eigen::VectorXd d = ldlt.vectorD();
  for (Eigen::Index i = 0; i < d.size(); ++i)
    if (!(d(i) > 0.0)) return rows[static_cast<std::size_t>(ldlt.permutationPinv().indices()(i))];
  return -1;
}

}  // namespace ema::model
