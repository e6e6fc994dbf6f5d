#include "interpolant.hpp"

#include <algorithm>
#include <cmath>

namespace ema::model::internal {

MonotoneCubic::MonotoneCubic(std::vector<double> x, std::vector<double> y) : x_(std::move(x)), y_(std::move(y)) {
  const std::size_t n = x_.size();
  d_.assign(n, 0.0);
  std::vector<double> delta(n - 1);
  for (std::size_t i = 0; i + 1 < n; ++i) delta[i] = (y_[i + 1] - y_[i]) / (x_[i + 1] - x_[i]);
  if (n == 2) {
    d_[0] = d_[1] = delta[0];
    return;
  }
  // Interior slopes: weighted harmonic mean (Fritsch-Butland), zero at a sign change; this keeps
  // the interpolant monotone wherever the data are.
  for (std::size_t i = 1; i + 1 < n; ++i) {
    if (delta[i - 1] * delta[i] <= 0.0) {
      d_[i] = 0.0;
    } else {
      const double h0 = x_[i] - x_[i - 1], h1 = x_[i + 1] - x_[i];
      const double w1 = 2.0 * h1 + h0, w2 = h1 + 2.0 * h0;
      d_[i] = (w1 + w2) / (w1 / delta[i - 1] + w2 / delta[i]);
    }
  }
  // End slopes: one-sided three-point formula, limited to keep monotonicity.
  auto end_slope = [](double h0, double h1, double del0, double del1) {
    double d = ((2.0 * h0 + h1) * del0 - h0 * del1) / (h0 + h1);
    if (d * del0 <= 0.0) d = 0.0;
    else if (del0 * del1 <= 0.0 && std::abs(d) > std::abs(3.0 * del0)) d = 3.0 * del0;
    return d;
  };
  d_[0] = end_slope(x_[1] - x_[0], x_[2] - x_[1], delta[0], delta[1]);
  d_[n - 1] = end_slope(x_[n - 1] - x_[n - 2], x_[n - 2] - x_[n - 3], delta[n - 2], delta[n - 3]);
}

std::size_t MonotoneCubic::Segment(double t) const {
  auto it = std::upper_bound(x_.begin(), x_.end(), t);
  std::size_t i = it == x_.begin() ? 0 : static_cast<std::size_t>(it - x_.begin()) - 1;
  return std::min(i, x_.size() - 2);
}

double MonotoneCubic::Value(double t) const {
  const std::size_t i = Segment(t);
  const double h = x_[i + 1] - x_[i], s = (t - x_[i]) / h;
  const double h00 = (1 + 2 * s) * (1 - s) * (1 - s), h10 = s * (1 - s) * (1 - s);
  const double h01 = s * s * (3 - 2 * s), h11 = s * s * (s - 1);
  return h00 * y_[i] + h10 * h * d_[i] + h01 * y_[i + 1] + h11 * h * d_[i + 1];
}

double MonotoneCubic::Slope(double t) const {
  const std::size_t i = Segment(t);
  const double h = x_[i + 1] - x_[i], s = (t - x_[i]) / h;
  const double d00 = 6 * s * s - 6 * s, d10 = 3 * s * s - 4 * s + 1;
  const double d01 = -6 * s * s + 6 * s, d11 = 3 * s * s - 2 * s;
  return (d00 * y_[i] + d01 * y_[i + 1]) / h + d10 * d_[i] + d11 * d_[i + 1];
}

double MonotoneCubic::ValueExtrapolated(double t) const {
  if (t < x_.front()) return y_.front() + d_.front() * (t - x_.front());
  if (t > x_.back()) return y_.back() + d_.back() * (t - x_.back());
  return Value(t);
}

double MonotoneCubic::Inverse(double v) const {
  if (v <= y_.front()) return d_.front() > 0 ? x_.front() + (v - y_.front()) / d_.front() : x_.front();
  if (v >= y_.back()) return d_.back() > 0 ? x_.back() + (v - y_.back()) / d_.back() : x_.back();
  auto it = std::upper_bound(y_.begin(), y_.end(), v);
  const std::size_t i = std::min(static_cast<std::size_t>(it - y_.begin()) - 1, x_.size() - 2);
  double lo = x_[i], hi = x_[i + 1];
  for (int iter = 0; iter < 200 && hi - lo > 1e-15 * (std::abs(lo) + std::abs(hi) + 1e-300); ++iter) {
    const double mid = 0.5 * (lo + hi);
    if (Value(mid) < v) lo = mid; else hi = mid;
  }
  return 0.5 * (lo + hi);
}

}  // namespace ema::model::internal
