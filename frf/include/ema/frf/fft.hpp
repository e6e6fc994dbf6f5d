// Real-to-complex FFT on FFTW with plans created once per length and reused. FFTW's planner is
// not thread-safe, so plan creation is serialised by a mutex; executing a plan on new arrays is
// thread-safe, so every RealFft owns its own aligned buffers and may run in its own thread.
#pragma once

#include <complex>
#include <memory>

namespace ema::frf {

class RealFft {
 public:
  /// Plans (or fetches the cached plan for) length n. DFT sign e^{-j2πkn/N} (spec §0), unscaled.
  explicit RealFft(int n);
  ~RealFft();
  RealFft(const RealFft&) = delete;
  RealFft& operator=(const RealFft&) = delete;

  int size() const { return n_; }
  int lines() const { return n_ / 2 + 1; }
  /// The aligned input buffer (n values) to fill before Execute().
  double* input() { return in_; }
  /// Transforms input() and returns the n/2 + 1 non-negative-frequency lines.
  const std::complex<double>* Execute();

 private:
  int n_;
  void* plan_;  // fftw_plan, owned by the process-wide cache
  double* in_;
  std::complex<double>* out_;
};

/// Number of distinct plans created so far (tests check that plans are reused).
int PlanCount();

}  // namespace ema::frf
