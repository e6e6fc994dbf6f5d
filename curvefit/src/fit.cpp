#include "ema/curvefit/fit.hpp"

#include <algorithm>
#include <chrono>

namespace ema::curvefit {

std::vector<SelectedPole> SelectPolesNarrowBand(const StabilisationDiagram& diagram, const FitOptions& options,
                                                std::string* note) {
  // A band of few lines supports few orders (the normal equations turn singular early), so a
  // physical pole is seen at only a handful of orders, and at those low orders its damping
  // still moves by more than the 5 % of the default criterion between orders. Relax both to
  // what such a band can show: damping stable to 20 %, a cluster over 3 orders.
  const int orders = static_cast<int>(diagram.orders.size());
  const int lines = static_cast<int>(diagram.frequency_hz.size());
  if (orders < 2 || lines > options.narrow_band_max_lines) return {};
  StabilisationDiagram relaxed = diagram;
  StabilityOptions stability = options.stability;
  stability.damping_tol = std::max(stability.damping_tol, 0.2);
  ClassifyStability(&relaxed, stability);
  AutoSelectOptions select = options.auto_select;
  select.min_orders = std::min(select.min_orders, 3);
  std::vector<SelectedPole> selected = SelectPolesAuto(relaxed, select);
  if (note && !selected.empty())
    *note = "narrow band (" + std::to_string(diagram.frequency_hz.size()) + " lines, orders " +
            std::to_string(diagram.order_min) + ".." + std::to_string(diagram.order_max) +
            "): poles selected with relaxed stability (damping within 20 %, clusters over 3 orders)";
  return selected;
}

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
    if (options.select_frequencies_hz.empty()) {
      std::string note;
      std::vector<SelectedPole> relaxed = SelectPolesNarrowBand(result.diagram, options, &note);
      if (relaxed.size() > result.selected.size()) {
        result.selected = std::move(relaxed);
        result.warnings.push_back(source + ": " + note);
      }
    }
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
