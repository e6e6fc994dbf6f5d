// Ceres logs through glog: unconfigured, its first warning prints "WARNING: Logging before
// InitGoogleLogging()" and every later one a "E… trust_region_minimizer.cc:…]" line on stderr —
// third-party lines a user of `ema` should never see; ema says what happened in its own words
// (a refinement's summary, a fit's error). Include only where Ceres (and so glog) is linked:
// curvefit/ and diagnose/ call QuietSolverLogging() before solving.
#pragma once

#include <glog/logging.h>

#include <mutex>

namespace ema {

inline void QuietSolverLogging() {
  static std::once_flag once;
  std::call_once(once, [] {
    if (!google::IsGoogleLoggingInitialized()) google::InitGoogleLogging("ema");
    FLAGS_logtostderr = false;
    FLAGS_alsologtostderr = false;
    FLAGS_stderrthreshold = google::GLOG_FATAL;
    FLAGS_minloglevel = google::GLOG_FATAL;
  });
}

}  // namespace ema
