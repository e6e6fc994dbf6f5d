#include "ema/frf/fft.hpp"

#include <fftw3.h>

#include <map>
#include <mutex>
#include <new>
#include <stdexcept>
#include <string>
#include <utility>

namespace ema::frf {

namespace {

enum class PlanKind { kRealToComplex, kComplexInPlace };

// The one planner lock of the program: FFTW's planner (plan creation and destruction) is not
// thread-safe, and every plan is made in this file.
std::mutex& PlannerMutex() {
  static std::mutex m;
  return m;
}

// Plans live for the whole process (one per kind and length); FFTW plans are read-only once made.
// The cache owns them: at exit it destroys every plan and lets FFTW free its planner state, so a
// leak checker sees nothing left (docs/reliability.md).
struct PlanCache {
  std::map<std::pair<PlanKind, int>, fftw_plan> plans;
  PlanCache() = default;
  PlanCache(const PlanCache&) = delete;
  PlanCache& operator=(const PlanCache&) = delete;
  ~PlanCache() {
    for (auto& [key, plan] : plans) fftw_destroy_plan(plan);
    fftw_cleanup();
  }
};

std::map<std::pair<PlanKind, int>, fftw_plan>& Plans() {
  static PlanCache cache;
  return cache.plans;
}

// The cached plan of (kind, n), made by `make` on the caller's buffers the first time. Planning
// with FFTW_ESTIMATE does not overwrite the buffers; planning on fftw_malloc'ed arrays keeps the
// SIMD alignment every transform's buffers also have, as new-array execution requires.
template <typename MakePlan>
fftw_plan CachedPlan(PlanKind kind, int n, MakePlan make) {
  std::lock_guard<std::mutex> lock(PlannerMutex());
  auto it = Plans().find({kind, n});
  if (it == Plans().end()) {
    fftw_plan plan = make();
    if (!plan) throw std::runtime_error("FFTW could not plan a transform of length " + std::to_string(n));
    it = Plans().emplace(std::make_pair(kind, n), plan).first;
  }
  return it->second;
}

}  // namespace

RealFft::RealFft(int n) : n_(n) {
  if (n < 2) throw std::invalid_argument("RealFft: length must be at least 2");
  in_ = static_cast<double*>(fftw_malloc(sizeof(double) * n));
  out_ = reinterpret_cast<std::complex<double>*>(fftw_malloc(sizeof(fftw_complex) * (n / 2 + 1)));
  if (!in_ || !out_) {
    fftw_free(in_);
    fftw_free(out_);
    throw std::bad_alloc();
  }
  try {
    plan_ = CachedPlan(PlanKind::kRealToComplex, n, [&] {
      return fftw_plan_dft_r2c_1d(n, in_, reinterpret_cast<fftw_complex*>(out_), FFTW_ESTIMATE);
    });
  } catch (...) {
    fftw_free(in_);
    fftw_free(out_);
    throw;
  }
}

RealFft::~RealFft() {
  fftw_free(in_);
  fftw_free(out_);
}

const std::complex<double>* RealFft::Execute() {
  fftw_execute_dft_r2c(static_cast<fftw_plan>(plan_), in_, reinterpret_cast<fftw_complex*>(out_));
  return out_;
}

ComplexFft::ComplexFft(int n) : n_(n) {
  if (n < 1) throw std::invalid_argument("ComplexFft: length must be at least 1");
  data_ = reinterpret_cast<std::complex<double>*>(fftw_malloc(sizeof(fftw_complex) * n));
  if (!data_) throw std::bad_alloc();
  try {
    plan_ = CachedPlan(PlanKind::kComplexInPlace, n, [&] {
      auto* buffer = reinterpret_cast<fftw_complex*>(data_);
      return fftw_plan_dft_1d(n, buffer, buffer, FFTW_FORWARD, FFTW_ESTIMATE);
    });
  } catch (...) {
    fftw_free(data_);
    throw;
  }
}

ComplexFft::~ComplexFft() { fftw_free(data_); }

void ComplexFft::Execute() {
  auto* buffer = reinterpret_cast<fftw_complex*>(data_);
  fftw_execute_dft(static_cast<fftw_plan>(plan_), buffer, buffer);
}

int PlanCount() {
  std::lock_guard<std::mutex> lock(PlannerMutex());
  return static_cast<int>(Plans().size());
}

}  // namespace ema::frf
