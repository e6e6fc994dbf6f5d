// Monotone piecewise-cubic Hermite interpolant (Fritsch-Carlson), private to the model module.
#pragma once

#include <vector>

namespace ema::model::internal {

class MonotoneCubic {
 public:
  MonotoneCubic() = default;
  /// x strictly increasing, y strictly monotone (checked by the caller), at least two points.
  MonotoneCubic(std::vector<double> x, std::vector<double> y);

  double Value(double t) const;
  double Slope(double t) const;
  /// Linear extrapolation with the end slopes outside [x0, xn].
  double ValueExtrapolated(double t) const;
  /// t with Value(t) = v for increasing data (bisection + Newton polish); linear extrapolation
  /// outside the range.
  double Inverse(double v) const;
  double XMin() const { return x_.front(); }
  double XMax() const { return x_.back(); }
  double YFirst() const { return y_.front(); }
  double YLast() const { return y_.back(); }

 private:
  std::size_t Segment(double t) const;
  std::vector<double> x_, y_, d_;
};

}  // namespace ema::model::internal
