// Stabilisation diagram picture (SVG or PNG through PLplot's cairo drivers).
#pragma once

#include <filesystem>
#include <vector>

#include "ema/curvefit/stabilisation.hpp"

namespace ema {

/// True for the picture formats PlotStabilisation can write (.svg, .png).
bool IsSupportedPlotPath(const std::filesystem::path& path);

/// Order (left axis) vs frequency with one letter per pole (s stable, d f+damping, v f+vector,
/// f frequency, o new; x impossible: negative damping), the sum of |FRF| on a log right axis and
/// the selected modes as vertical lines. Written atomically.
void PlotStabilisation(const std::filesystem::path& path, const curvefit::StabilisationDiagram& diagram,
                       const std::vector<curvefit::SelectedPole>& selected);

}  // namespace ema
