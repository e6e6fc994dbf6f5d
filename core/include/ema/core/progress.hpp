// Progress reporting for long computations, and their cancellation. The numerical core calls the
// callback; the CLI draws a bar, the Python bindings stop the computation on Ctrl-C through it.
#pragma once

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <functional>
#include <mutex>
#include <string_view>
#include <utility>

namespace ema {

/// Called with the fraction done (0..1) and a short stage name. May be empty (no reporting).
/// A computation may call it from its worker threads, but never from two threads at once (the
/// caller serialises the calls). It may throw to stop the computation (`Cancelled`, below): the
/// numerical core lets the exception through from any thread, stops its other workers at their
/// next step (`RunOnThreads`, core/parallel.hpp) and the exception reaches the caller.
using ProgressCallback = std::function<void(double fraction, std::string_view stage)>;

inline void ReportProgress(const ProgressCallback& progress, double fraction, std::string_view stage) {
  if (progress) progress(fraction, stage);
}

/// A stage of `total` steps shared out over threads: Step(), from any of them, counts one and
/// reports the share done, mapped onto [from, to], one call at a time. At most about a thousand
/// reports over the stage (every total/1000-th step, and the last): a million small steps make no
/// million calls, and a cancelling callback is still asked every thousandth of the stage. What the
/// callback throws comes out of Step(), and the callback is not called again by this stage: the
/// other threads stop at their next step, but until the exception has reached RunOnThreads and
/// raised its stop flag — a while under a sanitizer or on a loaded machine — they would still report
/// to a callback that has said stop. `stage` must outlive the object (a string literal).
class StepProgress {
 public:
  StepProgress(ProgressCallback progress, std::string_view stage, std::size_t total, double from = 0.0,
               double to = 1.0)
      : progress_(std::move(progress)), stage_(stage), total_(std::max<std::size_t>(total, 1)),
        every_(std::max<std::size_t>(total / 1000, 1)), from_(from), to_(to) {}
  void Step() {
    if (!progress_) return;
    std::lock_guard<std::mutex> lock(mutex_);
    if (stopped_) return;
    ++done_;
    if (done_ % every_ != 0 && done_ != total_) return;
    const double share = static_cast<double>(std::min(done_, total_)) / static_cast<double>(total_);
    try {
      progress_(from_ + (to_ - from_) * share, stage_);
    } catch (...) {
      stopped_ = true;
      throw;
    }
  }

 private:
  ProgressCallback progress_;
  std::string_view stage_;
  std::size_t total_, every_, done_ = 0;
  bool stopped_ = false;  // the callback threw: not called again
  double from_, to_;
  std::mutex mutex_;
};

/// What a progress callback throws to stop the computation that called it (the Python bindings
/// on Ctrl-C). Not a std::exception on purpose: code that turns a failure into a result (`ema
/// run`'s failed step, a refinement that falls back to the PolyMAX poles) catches std::exception
/// or one of its kinds, and must let a cancellation through to whoever asked for it.
struct Cancelled {
  const char* what() const noexcept { return "cancelled"; }
};

/// A flag one thread raises and a computation's progress callback checks from whichever thread
/// the computation calls it on (`Callback()`): once raised, the next progress step throws
/// `Cancelled`.
class CancelFlag {
 public:
  void Cancel() noexcept { cancelled_.store(true, std::memory_order_relaxed); }
  bool IsCancelled() const noexcept { return cancelled_.load(std::memory_order_relaxed); }
  void ThrowIfCancelled() const {
    if (IsCancelled()) throw Cancelled{};
  }
  /// A progress callback that throws `Cancelled` once the flag is raised and otherwise passes the
  /// step on to `inner` (may be empty). The flag must outlive the callback.
  ProgressCallback Callback(ProgressCallback inner = {}) const {
    return [this, inner = std::move(inner)](double fraction, std::string_view stage) {
      ThrowIfCancelled();
      if (inner) inner(fraction, stage);
    };
  }

 private:
  std::atomic<bool> cancelled_{false};
};

}  // namespace ema
