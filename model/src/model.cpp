// Small helpers of the model value types.
#include "ema/model/model.hpp"

#include <algorithm>

namespace ema::model {

std::string Law::KindName() const {
  static const char* kNames[] = {"linear", "table", "air_film", "hertz", "series", "micro_slip"};
  return kNames[value.index()];
}

bool Law::IsNonlinear() const {
  if (std::holds_alternative<LinearLaw>(value) || std::holds_alternative<MicroSlipLaw>(value)) return false;
  if (const auto* series = std::get_if<SeriesLaw>(&value)) {
    return std::any_of(series->elements.begin(), series->elements.end(),
                       [](const Law& e) { return e.IsNonlinear(); });
  }
  return true;
}

bool Law::IsNonlinearInTime() const {
  if (std::holds_alternative<LinearLaw>(value)) return false;
  if (const auto* series = std::get_if<SeriesLaw>(&value)) {
    return std::any_of(series->elements.begin(), series->elements.end(),
                       [](const Law& e) { return e.IsNonlinearInTime(); });
  }
  return true;
}

double Damping::RatioOfMode(int elastic_mode_index) const {
  if (ratios.empty()) return ratio;
  const auto i = std::min<std::size_t>(static_cast<std::size_t>(std::max(0, elastic_mode_index)), ratios.size() - 1);
  return ratios[i];
}

const Body* Model::FindBody(const std::string& body_name) const {
  for (const Body& b : bodies)
    if (b.name == body_name) return &b;
  return nullptr;
}

Body* Model::FindBody(const std::string& body_name) {
  for (Body& b : bodies)
    if (b.name == body_name) return &b;
  return nullptr;
}

std::string Model::Where(int line) const {
  const std::string file = origin.empty() ? std::string("model") : origin;
  return line > 0 ? file + ":" + std::to_string(line) : file;
}

}  // namespace ema::model
