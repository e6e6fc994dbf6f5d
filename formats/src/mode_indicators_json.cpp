#include "ema/formats/mode_indicators_json.hpp"

#include <vector>

#include "ema/curvefit/mode_indicators.hpp"
#include "ema/formats/json_codecs.hpp"

namespace ema::formats {

namespace {

// One JSON array per column of `values` (a singular value of the CMIF, an eigenvalue of the MMIF),
// null where not finite.
nlohmann::json IndicatorColumns(const Eigen::MatrixXd& values) {
  nlohmann::json out = nlohmann::json::array();
  for (int c = 0; c < values.cols(); ++c) {
    nlohmann::json col = nlohmann::json::array();
    for (int k = 0; k < values.rows(); ++k) col.push_back(NumberOrNull(values(k, c)));
    out.push_back(std::move(col));
  }
  return out;
}

}  // namespace

void AddModeIndicatorsJson(nlohmann::json* stabilisation, const FrfSet& frfs, const curvefit::FitDataOptions& options,
                           const std::string& source) {
  const curvefit::FitData data = curvefit::PrepareFitData(frfs, options, source);
  const curvefit::ModeIndicators mi = curvefit::ComputeModeIndicators(data);
  const std::vector<double> f(mi.frequency_hz.data(), mi.frequency_hz.data() + mi.frequency_hz.size());
  (*stabilisation)["cmif"] = {{"frequency_hz", f}, {"values", IndicatorColumns(mi.cmif)}};
  (*stabilisation)["mmif"] = {{"frequency_hz", f}, {"values", IndicatorColumns(mi.mmif)}};
}

}  // namespace ema::formats
