// The FFT seam (frf/fft.hpp): both transforms against a direct DFT, plan reuse, and concurrent
// construction (the one planner lock).
#include "ema/frf/fft.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <thread>
#include <vector>

namespace ema::frf {
namespace {

constexpr double kTwoPi = 6.283185307179586;

std::vector<std::complex<double>> DirectDft(const std::vector<std::complex<double>>& x) {
  const int n = static_cast<int>(x.size());
  std::vector<std::complex<double>> out(n);
  for (int k = 0; k < n; ++k)
    for (int t = 0; t < n; ++t) out[k] += x[t] * std::polar(1.0, -kTwoPi * k * t / n);
  return out;
}

// Rounding bound for an n-term sum of terms up to |x_t|: n · ε · Σ|x_t| with ε ~ 1e-16 and a
// factor 100 of margin (the direct DFT's own twiddle factors carry rounding too).
double Tolerance(const std::vector<std::complex<double>>& x) {
  double sum = 0.0;
  for (const auto& v : x) sum += std::abs(v);
  return 1e-14 * static_cast<double>(x.size()) * sum;
}

std::vector<std::complex<double>> Signal(int n) {
  std::vector<std::complex<double>> x(n);
  for (int t = 0; t < n; ++t) x[t] = {std::sin(0.7 * t) + 0.1 * t, std::cos(1.3 * t) - 0.05 * t * t};
  return x;
}

TEST(Fft, ComplexMatchesDirectDftOnAnOddLength) {
  // 45 = 3^2 * 5 (not a power of two).
  const auto x = Signal(45);
  ComplexFft fft(45);
  for (int t = 0; t < 45; ++t) fft.data()[t] = x[t];
  fft.Execute();
  const auto expected = DirectDft(x);
  const double tolerance = Tolerance(x);  // ~7e-10 against values up to ~1500
  for (int k = 0; k < 45; ++k) EXPECT_LT(std::abs(fft.data()[k] - expected[k]), tolerance) << "line " << k;
}

TEST(Fft, RealMatchesDirectDftOfTheRealPart) {
  auto x = Signal(30);
  for (auto& v : x) v = v.real();
  RealFft fft(30);
  for (int t = 0; t < 30; ++t) fft.input()[t] = x[t].real();
  const std::complex<double>* lines = fft.Execute();
  const auto expected = DirectDft(x);
  ASSERT_EQ(fft.lines(), 16);
  const double tolerance = Tolerance(x);
  for (int k = 0; k < fft.lines(); ++k) EXPECT_LT(std::abs(lines[k] - expected[k]), tolerance) << "line " << k;
}

TEST(Fft, OnePlanPerKindAndLength) {
  // 4097 and 4099 are lengths no other test uses; the real and complex plans of one length are
  // two plans, a second object of either kind reuses its plan.
  const int before = PlanCount();
  { ComplexFft a(4097); }
  { RealFft b(4097); }
  EXPECT_EQ(PlanCount(), before + 2);
  { ComplexFft a(4097); RealFft b(4097); }
  EXPECT_EQ(PlanCount(), before + 2);
}

TEST(Fft, TransformsMadeInManyThreadsAgree) {
  // Plans are made under the one planner lock; each object executes on its own buffers.
  const auto x = Signal(4099);
  std::vector<std::vector<std::complex<double>>> results(4);
  std::vector<std::thread> threads;
  for (int i = 0; i < 4; ++i)
    threads.emplace_back([&, i] {
      ComplexFft fft(4099);
      for (int t = 0; t < 4099; ++t) fft.data()[t] = x[t];
      fft.Execute();
      results[i].assign(fft.data(), fft.data() + 4099);
    });
  for (auto& t : threads) t.join();
  for (int i = 1; i < 4; ++i) EXPECT_EQ(results[i], results[0]);
}

}  // namespace
}  // namespace ema::frf
