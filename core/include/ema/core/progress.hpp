// Progress reporting for long computations. The numerical core calls it; the CLI draws a bar.
#pragma once

#include <functional>
#include <string_view>

namespace ema {

/// Called with the fraction done (0..1) and a short stage name. May be empty (no reporting).
using ProgressCallback = std::function<void(double fraction, std::string_view stage)>;

inline void ReportProgress(const ProgressCallback& progress, double fraction, std::string_view stage) {
  if (progress) progress(fraction, stage);
}

}  // namespace ema
