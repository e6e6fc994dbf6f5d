#include "ema/correlation/pairing.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace ema::correlation {

std::vector<int> SolveAssignment(const Eigen::MatrixXd& cost) {
  const int rows = static_cast<int>(cost.rows());
  const int cols = static_cast<int>(cost.cols());
  const int n = std::max(rows, cols);
  if (n == 0) return {};
  // Pad to square with zero cost: a dummy row/column means "left out".
  Eigen::MatrixXd c = Eigen::MatrixXd::Zero(n, n);
  c.topLeftCorner(rows, cols) = cost;
  const double inf = std::numeric_limits<double>::infinity();
  // Shortest augmenting paths with row/column potentials u, v (1-based, index 0 is a sentinel).
  std::vector<double> u(n + 1, 0.0), v(n + 1, 0.0);
  std::vector<int> match_col(n + 1, 0), way(n + 1, 0);  // match_col[j] = row matched to column j
  for (int i = 1; i <= n; ++i) {
    match_col[0] = i;
    int j0 = 0;
    std::vector<double> min_v(n + 1, inf);
    std::vector<char> used(n + 1, 0);
    do {
      used[j0] = 1;
      const int i0 = match_col[j0];
      double delta = inf;
      int j1 = 0;
      for (int j = 1; j <= n; ++j) {
        if (used[j]) continue;
        const double reduced = c(i0 - 1, j - 1) - u[i0] - v[j];
        if (reduced < min_v[j]) {
          min_v[j] = reduced;
          way[j] = j0;
        }
        if (min_v[j] < delta) {
          delta = min_v[j];
          j1 = j;
        }
      }
      for (int j = 0; j <= n; ++j) {
        if (used[j]) {
          u[match_col[j]] += delta;
          v[j] -= delta;
        } else {
          min_v[j] -= delta;
        }
      }
      j0 = j1;
    } while (match_col[j0] != 0);
    do {  // flip the augmenting path
      const int j1 = way[j0];
      match_col[j0] = match_col[j1];
      j0 = j1;
    } while (j0 != 0);
  }
  std::vector<int> row_to_col(rows, -1);
  for (int j = 1; j <= n; ++j) {
    const int i = match_col[j] - 1;
    if (i >= 0 && i < rows && j - 1 < cols) row_to_col[i] = j - 1;
  }
  return row_to_col;
}

Pairing PairModes(const Eigen::MatrixXd& mac, const Eigen::VectorXd& test_hz, const Eigen::VectorXd& model_hz,
                  const PairingOptions& options) {
  const Eigen::Index nt = mac.rows();
  const Eigen::Index nm = mac.cols();
  auto relative_difference = [&](Eigen::Index i, Eigen::Index j) {
    const double a = test_hz(i), b = model_hz(j);
    const double denominator = std::max(std::abs(a), std::abs(b));
    return denominator > 0.0 ? std::abs(a - b) / denominator : 0.0;
  };
  auto admissible = [&](Eigen::Index i, Eigen::Index j) {
    return mac(i, j) >= options.mac_min && relative_difference(i, j) <= options.max_relative_frequency_difference;
  };
  // Cost = −(MAC − w·Δf_rel) for admissible pairs, 0 otherwise (same as leaving both unpaired),
  // so minimising the cost maximises the total admissible MAC.
  Eigen::MatrixXd cost = Eigen::MatrixXd::Zero(nt, nm);
  for (Eigen::Index i = 0; i < nt; ++i)
    for (Eigen::Index j = 0; j < nm; ++j)
      if (admissible(i, j)) cost(i, j) = -(mac(i, j) - options.frequency_weight * relative_difference(i, j));
  const std::vector<int> assigned = SolveAssignment(cost);
  Pairing result;
  std::vector<char> model_used(nm, 0);
  for (Eigen::Index i = 0; i < nt; ++i) {
    const int j = assigned[i];
    if (j >= 0 && admissible(i, j)) {
      result.pairs.push_back({static_cast<int>(i), j, mac(i, j)});
      model_used[j] = 1;
    } else {
      result.unpaired_test.push_back(static_cast<int>(i));
    }
  }
  for (Eigen::Index j = 0; j < nm; ++j)
    if (!model_used[j]) result.unpaired_model.push_back(static_cast<int>(j));
  return result;
}

}  // namespace ema::correlation
