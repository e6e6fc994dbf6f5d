#include "mode_indicators_json.hpp"

#include <cmath>

#include "ema/curvefit/mode_indicators.hpp"

namespace ema {

namespace {

nlohmann::json Columns(const Eigen::MatrixXd& values) {
  nlohmann::json out = nlohmann::json::array();
  for (int c = 0; c < values.cols(); ++c) {
    nlohmann::json col = nlohmann::json::array();
    for (int k = 0; k < values.rows(); ++k)
      col.push_back(std::isfinite(values(k, c)) ? nlohmann::json(values(k, c)) : nlohmann::json(nullptr));
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
  (*stabilisation)["cmif"] = {{"frequency_hz", f}, {"values", Columns(mi.cmif)}};
  (*stabilisation)["mmif"] = {{"frequency_hz", f}, {"values", Columns(mi.mmif)}};
}

}  // namespace ema
