#include "ema/frf/fft.hpp"

#include <fftw3.h>

#include <map>
#include <mutex>
#include <new>
#include <stdexcept>

namespace ema::frf {

namespace {

std::mutex& PlannerMutex() {
  static std::mutex m;
  return m;
}

// Plans live for the whole process (one per length); FFTW plans are read-only once made. The
// cache owns them: at exit it destroys every plan and lets FFTW free its planner state, so a leak
// checker sees nothing left (docs/reliability.md).
struct PlanCache {
  std::map<int, fftw_plan> plans;
  PlanCache() = default;
  PlanCache(const PlanCache&) = delete;
  PlanCache& operator=(const PlanCache&) = delete;
  ~PlanCache() {
    for (auto& [n, plan] : plans) fftw_destroy_plan(plan);
    fftw_cleanup();
  }
};

std::map<int, fftw_plan>& Plans() {
  static PlanCache cache;
  return cache.plans;
}

}  // namespace

RealFft::RealFft(int n) : n_(n) {
  if (n < 2) throw std::invalid_argument("RealFft: length must be at least 2");
  in_ = static_cast<double*>(fftw_malloc(sizeof(double) * n));
  out_ = reinterpret_cast<std::complex<double>*>(fftw_malloc(sizeof(fftw_complex) * (n / 2 + 1)));
  if (!in_ || !out_) throw std::bad_alloc();
  std::lock_guard<std::mutex> lock(PlannerMutex());
  auto it = Plans().find(n);
  if (it == Plans().end()) {
    // FFTW_ESTIMATE does not overwrite the buffers; planning on fftw_malloc'ed arrays keeps the
    // SIMD alignment every RealFft buffer also has, as new-array execution requires.
    fftw_plan plan = fftw_plan_dft_r2c_1d(n, in_, reinterpret_cast<fftw_complex*>(out_), FFTW_ESTIMATE);
    if (!plan) throw std::runtime_error("FFTW could not plan a real FFT of length " + std::to_string(n));
    it = Plans().emplace(n, plan).first;
  }
  plan_ = it->second;
}

RealFft::~RealFft() {
  fftw_free(in_);
  fftw_free(out_);
}

const std::complex<double>* RealFft::Execute() {
  fftw_execute_dft_r2c(static_cast<fftw_plan>(plan_), in_, reinterpret_cast<fftw_complex*>(out_));
  return out_;
}

int PlanCount() {
  std::lock_guard<std::mutex> lock(PlannerMutex());
  return static_cast<int>(Plans().size());
}

}  // namespace ema::frf
