#include "ema/formats/quality_json.hpp"

#include "ema/formats/json_codecs.hpp"

namespace ema::formats {

namespace {

nlohmann::json QualityDofJson(const Dof& d) { return {{"node", d.node}, {"dir", DirectionName(d.direction)}}; }

}  // namespace

nlohmann::json QualityJson(const frf::FrfQualityReport& q, const std::vector<curvefit::ModeComplexityCheck>& modes,
                           const frf::QualityOptions& options) {
  using frf::VerdictToString;
  nlohmann::json rec = nlohmann::json::array();
  for (const auto& c : q.reciprocity)
    rec.push_back({{"i", QualityDofJson(c.dof_i)}, {"j", QualityDofJson(c.dof_j)},
                   {"relative_difference", NumberOrNull(c.relative_difference)},
                   {"amplitude_ratio", NumberOrNull(c.amplitude_ratio)}, {"tolerance", options.reciprocity_tolerance},
                   {"verdict", VerdictToString(c.verdict)}, {"reason", c.reason}});
  nlohmann::json dp = nlohmann::json::array();
  for (const auto& c : q.driving_points)
    dp.push_back({{"dof", QualityDofJson(c.dof)}, {"resonances", c.resonances}, {"flipped", c.flipped},
                  {"flipped_frequencies_hz", c.flipped_frequencies_hz},
                  {"sign_consistency", NumberOrNull(c.sign_consistency)},
                  {"verdict", VerdictToString(c.verdict)}, {"reason", c.reason}});
  nlohmann::json frfs = nlohmann::json::array();
  for (const auto& s : q.frfs)
    frfs.push_back({{"response", QualityDofJson(s.response)}, {"reference", QualityDofJson(s.reference)},
                    {"mean_coherence", NumberOrNull(s.mean_coherence)},
                    {"low_coherence_fraction", NumberOrNull(s.low_coherence_fraction)},
                    {"averages", s.averages}, {"median_random_error", NumberOrNull(s.median_random_error)},
                    {"max_random_error", NumberOrNull(s.max_random_error)},
                    {"coherence_verdict", VerdictToString(s.coherence_verdict)},
                    {"scatter_verdict", VerdictToString(s.scatter_verdict)}, {"reason", s.reason}});
  nlohmann::json map = nullptr;
  if (q.has_coherence) {
    const auto& m = q.coherence_map;
    nlohmann::json rows = nlohmann::json::array();
    for (int r = 0; r < m.coherence.rows(); ++r) {
      nlohmann::json row = nlohmann::json::array();
      for (int k = 0; k < m.coherence.cols(); ++k) row.push_back(NumberOrNull(m.coherence(r, k)));
      rows.push_back(std::move(row));
    }
    map = {{"frequency_hz", std::vector<double>(m.frequency_hz.data(), m.frequency_hz.data() + m.frequency_hz.size())},
           {"labels", m.labels},
           {"coherence", rows}};
  }
  nlohmann::json mj = nlohmann::json::array();
  int mode_warnings = 0;
  for (const auto& c : modes) {
    mode_warnings += c.verdict == frf::Verdict::kWarn;
    mj.push_back({{"mode", c.index + 1}, {"frequency_hz", NumberOrNull(c.frequency_hz)}, {"mpc", NumberOrNull(c.mpc)},
                  {"mpd_deg", NumberOrNull(c.mpd_deg)}, {"mcf", NumberOrNull(c.mcf)},
                  {"verdict", VerdictToString(c.verdict)}, {"reason", c.reason}});
  }
  const int warnings = q.WarningCount() + mode_warnings;
  // Reasons, labels and notes name DOFs and files: valid UTF-8 whatever bytes they hold.
  return ValidUtf8({{"verdict", warnings > 0 ? "warn" : "pass"},
                    {"warnings", warnings},
                    {"thresholds",
                     {{"reciprocity_tolerance", options.reciprocity_tolerance},
                      {"resonance_level", options.resonance_level},
                      {"coherence_min", options.coherence_min},
                      {"coherence_max_low_fraction", options.coherence_max_low_fraction},
                      {"scatter_max", options.scatter_max}}},
                    {"reciprocity", rec},
                    {"driving_points", dp},
                    {"frfs", frfs},
                    {"coherence_map", map},
                    {"modes", mj},
                    {"notes", q.notes}});
}

}  // namespace ema::formats
