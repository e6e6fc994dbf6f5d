#include "quality_json.hpp"

#include <cmath>
#include <sstream>

#include "ema/formats/json_codecs.hpp"

namespace ema {

namespace {

nlohmann::json Num(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); }

nlohmann::json DofJson(const Dof& d) { return {{"node", d.node}, {"dir", DirectionName(d.direction)}}; }

}  // namespace

nlohmann::json QualityJson(const frf::FrfQualityReport& q, const std::vector<curvefit::ModeComplexityCheck>& modes,
                           const frf::QualityOptions& options) {
  using frf::VerdictToString;
  nlohmann::json rec = nlohmann::json::array();
  for (const auto& c : q.reciprocity)
    rec.push_back({{"i", DofJson(c.dof_i)}, {"j", DofJson(c.dof_j)}, {"relative_difference", Num(c.relative_difference)},
                   {"amplitude_ratio", Num(c.amplitude_ratio)}, {"tolerance", options.reciprocity_tolerance},
                   {"verdict", VerdictToString(c.verdict)}, {"reason", c.reason}});
  nlohmann::json dp = nlohmann::json::array();
  for (const auto& c : q.driving_points)
    dp.push_back({{"dof", DofJson(c.dof)}, {"resonances", c.resonances}, {"flipped", c.flipped},
                  {"flipped_frequencies_hz", c.flipped_frequencies_hz}, {"sign_consistency", Num(c.sign_consistency)},
                  {"verdict", VerdictToString(c.verdict)}, {"reason", c.reason}});
  nlohmann::json frfs = nlohmann::json::array();
  for (const auto& s : q.frfs)
    frfs.push_back({{"response", DofJson(s.response)}, {"reference", DofJson(s.reference)},
                    {"mean_coherence", Num(s.mean_coherence)}, {"low_coherence_fraction", Num(s.low_coherence_fraction)},
                    {"averages", s.averages}, {"median_random_error", Num(s.median_random_error)},
                    {"max_random_error", Num(s.max_random_error)},
                    {"coherence_verdict", VerdictToString(s.coherence_verdict)},
                    {"scatter_verdict", VerdictToString(s.scatter_verdict)}, {"reason", s.reason}});
  nlohmann::json map = nullptr;
  if (q.has_coherence) {
    const auto& m = q.coherence_map;
    nlohmann::json rows = nlohmann::json::array();
    for (int r = 0; r < m.coherence.rows(); ++r) {
      nlohmann::json row = nlohmann::json::array();
      for (int k = 0; k < m.coherence.cols(); ++k) row.push_back(Num(m.coherence(r, k)));
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
    mj.push_back({{"mode", c.index + 1}, {"frequency_hz", Num(c.frequency_hz)}, {"mpc", Num(c.mpc)},
                  {"mpd_deg", Num(c.mpd_deg)}, {"mcf", Num(c.mcf)}, {"verdict", VerdictToString(c.verdict)},
                  {"reason", c.reason}});
  }
  const int warnings = q.WarningCount() + mode_warnings;
  // Reasons, labels and notes name DOFs and files: valid UTF-8 whatever bytes they hold.
  return formats::ValidUtf8({{"verdict", warnings > 0 ? "warn" : "pass"},
          {"warnings", warnings},
          {"thresholds",
           {{"reciprocity_tolerance", options.reciprocity_tolerance}, {"resonance_level", options.resonance_level},
            {"coherence_min", options.coherence_min}, {"coherence_max_low_fraction", options.coherence_max_low_fraction},
            {"scatter_max", options.scatter_max}}},
          {"reciprocity", rec},
          {"driving_points", dp},
          {"frfs", frfs},
          {"coherence_map", map},
          {"modes", mj},
          {"notes", q.notes}});
}

std::string QualityText(const frf::FrfQualityReport& q, const std::vector<curvefit::ModeComplexityCheck>& modes) {
  std::ostringstream out;
  auto section = [&](const std::string& name, int n, int warn) {
    out << name << ": " << n << " checked, " << warn << " warn" << (warn == 0 && n > 0 ? " (pass)" : "") << "\n";
  };
  int w = 0;
  for (const auto& c : q.reciprocity) w += c.verdict == frf::Verdict::kWarn;
  section("reciprocity", static_cast<int>(q.reciprocity.size()), w);
  for (const auto& c : q.reciprocity) out << "  " << frf::VerdictToString(c.verdict) << "  " << c.reason << "\n";
  w = 0;
  for (const auto& c : q.driving_points) w += c.verdict == frf::Verdict::kWarn;
  section("driving points", static_cast<int>(q.driving_points.size()), w);
  for (const auto& c : q.driving_points) out << "  " << frf::VerdictToString(c.verdict) << "  " << c.reason << "\n";
  int wc = 0, ws = 0;
  for (const auto& s : q.frfs) {
    wc += s.coherence_verdict == frf::Verdict::kWarn;
    ws += s.scatter_verdict == frf::Verdict::kWarn;
  }
  section("coherence", q.has_coherence ? static_cast<int>(q.frfs.size()) : 0, wc);
  section("impact-to-impact scatter", q.has_averages && q.has_coherence ? static_cast<int>(q.frfs.size()) : 0, ws);
  for (const auto& s : q.frfs)
    if (!s.reason.empty())
      out << "  warn  " << DofName(s.response) << "/" << DofName(s.reference) << ": " << s.reason << "\n";
  if (!modes.empty()) {
    w = 0;
    for (const auto& c : modes) w += c.verdict == frf::Verdict::kWarn;
    section("mode complexity", static_cast<int>(modes.size()), w);
    for (const auto& c : modes) out << "  " << frf::VerdictToString(c.verdict) << "  " << c.reason << "\n";
  }
  for (const auto& n : q.notes) out << "note: " << n << "\n";
  return out.str();
}

}  // namespace ema
