// Anti-alias filtering shared by the modal and the time-domain simulators (private).
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

namespace ema::acquisition::internal {

constexpr double kPi = 3.14159265358979323846;

// Zero-phase low-pass FIR on the fine grid (Kaiser-windowed sinc), cut-off at half the output
// Nyquist band edge: pass to 0.4 fs_out, stop from 0.6 fs_out (~80 dB), so nothing aliases
// below 0.4 fs_out after decimation. Every channel gets the same filter, which cancels in H.
inline std::vector<double> DesignAntiAlias(int oversampling) {
  const int half = 16 * oversampling;
  const double cutoff = 0.5 / oversampling;  // cycles per fine sample
  const double beta = 7.86;                  // Kaiser beta for ~80 dB stop band
  const double i0_beta = std::cyl_bessel_i(0.0, beta);
  std::vector<double> h(2 * half + 1);
  double sum = 0.0;
  for (int k = -half; k <= half; ++k) {
    const double x = 2.0 * cutoff * k;
    const double sinc = k == 0 ? 1.0 : std::sin(kPi * x) / (kPi * x);
    const double r = static_cast<double>(k) / half;
    const double w = std::cyl_bessel_i(0.0, beta * std::sqrt(std::max(0.0, 1.0 - r * r))) / i0_beta;
    h[k + half] = 2.0 * cutoff * sinc * w;
    sum += h[k + half];
  }
  for (double& v : h) v /= sum;  // unit DC gain
  return h;
}

// y[n] = sum_k h[k] x[n*os + half - k + half] with x indexed from fine time -half.
template <typename T>
std::vector<T> FilterDecimate(const std::vector<T>& fine, const std::vector<double>& h, int oversampling, int samples) {
  const int taps = static_cast<int>(h.size());
  std::vector<T> out(samples, T{});
  for (int n = 0; n < samples; ++n) {
    const T* x = fine.data() + static_cast<size_t>(n) * oversampling;  // fine index n*os - half .. n*os + half
    T acc{};
    for (int k = 0; k < taps; ++k) acc += h[k] * x[k];
    out[n] = acc;
  }
  return out;
}

}  // namespace ema::acquisition::internal
