// The program's one FFT seam, on FFTW: real-to-complex (FRF estimation) and complex-to-complex
// (PolyMAX lag sums) transforms, with plans created once per kind and length and reused. FFTW's
// planner is not thread-safe, so every plan of the program is made here under one lock; executing
// a plan on new arrays is thread-safe, so every transform object owns its own aligned buffers
// and may run in its own thread. Plans are destroyed at exit (leak checkers see nothing left).
#pragma once

#include <complex>

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

/// Forward complex-to-complex transform of length n, in place: X_k = sum_n x_n e^{-j2πkn/N},
/// unscaled (the same sign as RealFft).
class ComplexFft {
 public:
  /// Plans (or fetches the cached plan for) length n >= 1.
  explicit ComplexFft(int n);
  ~ComplexFft();
  ComplexFft(const ComplexFft&) = delete;
  ComplexFft& operator=(const ComplexFft&) = delete;

  int size() const { return n_; }
  /// The aligned buffer (n values): fill it, Execute(), read the transform back from it.
  std::complex<double>* data() { return data_; }
  void Execute();

 private:
  int n_;
  void* plan_;  // fftw_plan, owned by the process-wide cache
  std::complex<double>* data_;
};

/// Number of distinct plans (real and complex) created so far; tests check that plans are reused.
int PlanCount();

}  // namespace ema::frf
