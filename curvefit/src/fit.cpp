#include "ema/curvefit/fit.hpp"

#include <chrono>

namespace ema::curvefit {

FitResult Fit(const FrfSet& frfs, const FitOptions& options, const std::string& source,
              const ProgressCallback& progress) {
  using Clock = std::chrono::steady_clock;
  const auto t0 = Clock::now();
  FitResult result;
  const FitData data = PrepareFitData(frfs, options.data, source);
  result.transposed = data.transposed;
  result.warnings = data.warnings;
  if (options.method == FitMethod::kPeak) {
    result.modes = PeakPick(data, options.peak);
  } else {
    result.diagram = EstimatePoles(data, options.polymax, progress, &result.timing.polymax);
    for (size_t k = data.warnings.size(); k < result.diagram.warnings.size(); ++k)
      result.warnings.push_back(result.diagram.warnings[k]);
    const double t1 = ThreadCpuSeconds();
    ClassifyStability(&result.diagram, options.stability);
    result.selected = options.select_frequencies_hz.empty()
                          ? SelectPolesAuto(result.diagram, options.auto_select)
                          : SelectPolesNear(result.diagram, options.select_frequencies_hz);
    const double t2 = ThreadCpuSeconds();
    if (!result.selected.empty()) {
      LsfdResult lsfd = EstimateModeShapes(data, result.selected, options.lsfd);
      result.modes = std::move(lsfd.modes);
      result.synthesis_error = lsfd.synthesis_error;
      for (const auto& w : lsfd.warnings) result.warnings.push_back(source + ": " + w);
    } else {
      result.modes.dofs = data.outputs;
      result.warnings.push_back(source + ": no stable poles found; no modes selected");
    }
    const double t3 = ThreadCpuSeconds();
    result.timing.stabilisation_and_selection = t2 - t1;
    result.timing.lsfd = t3 - t2;
  }
  result.modes.source = source;
  result.timing.total = std::chrono::duration<double>(Clock::now() - t0).count();
  return result;
}

}  // namespace ema::curvefit
