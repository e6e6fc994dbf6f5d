#include "words.hpp"

#include <cmath>
#include <cstdio>
#include <variant>

#include "ema/core/text.hpp"
#include "ema/model/model.hpp"

namespace ema::report {

std::string Significant(double value, int digits) {
  char text[48];
  std::snprintf(text, sizeof text, "%.*g", digits, value);
  return text;
}

std::string RehearsalWords(const formats::ProjectTest& test) {
  if (!test.plan) return "";
  return "simulated from " + test.plan->filename().string() + " on " +
         (test.truth ? test.truth->filename().string() : std::string("the project's model")) +
         " (a rehearsal, not a measurement)";
}

std::string SelectText(const std::vector<double>& frequencies_hz) {
  if (frequencies_hz.empty()) return "auto";
  std::string list;
  for (double f : frequencies_hz) {
    if (!list.empty()) list += ',';
    list += ExactNumberText(f);
  }
  return list;
}

bool SeveralTestsOfOneSetup(const std::vector<diagnose::ModeComparison>& modes) {
  for (const diagnose::ModeComparison& a : modes)
    for (const diagnose::ModeComparison& b : modes)
      if (a.setup == b.setup && a.test != b.test) return true;
  return false;
}

std::string TestModeWords(const diagnose::ModeComparison& mode, bool name_test) {
  const std::string number = "mode " + std::to_string(mode.test_mode + 1);
  if (!name_test) return number + (mode.setup.empty() ? "" : " of " + mode.setup);
  return number + " of test " + std::to_string(mode.test + 1) + (mode.setup.empty() ? "" : " (" + mode.setup + ")");
}

std::string Percent(double probability) {
  char text[32];
  std::snprintf(text, sizeof text, "%.1f %%", 100.0 * probability);
  return text;
}

std::string ParameterWords(const diagnose::FittedParameter& p, const model::Effect* e) {
  const bool sigma = std::isfinite(p.sigma);
  auto with = [&](double scale, const std::string& unit, const std::string& name) {
    return name + Significant(p.value * scale) + (sigma ? " ± " + Significant(std::abs(p.sigma * scale), 2) : "") + unit;
  };
  const bool hertz = e && e->law && std::holds_alternative<model::HertzLaw>(e->law->value);
  if (p.name == "modulus" || hertz) {
    const double radius = hertz ? std::get<model::HertzLaw>(e->law->value).radius : kNaN;
    return with(1e-9, " GPa", "Hertz contact E' = ") +
           (std::isfinite(radius) ? " (R' = " + Significant(radius * 1e3) + " mm)" : "");
  }
  switch (p.effect_kind) {
    case model::EffectKind::kSeriesCompliance:
    case model::EffectKind::kGroundSpring:
      return with(1e-6, " N/µm", "k = ");
    case model::EffectKind::kAddedMass:
      return with(1e3, " g per point", "");
    case model::EffectKind::kOperatingPoint:
      return std::abs(p.value) < 1e-3 ? with(1e6, " µm", "value = ") : with(1.0, "", "value = ");
    case model::EffectKind::kStiffnessScale:
    case model::EffectKind::kMassScale:
      break;
  }
  return with(1.0, "", "factor ");
}

std::string EffectValuesWords(const pipeline::EffectFinding& f) {
  std::string out;
  for (const diagnose::FittedParameter& p : f.parameters) out += (out.empty() ? "" : "; ") + ParameterWords(p, &f.effect);
  if (f.springs.empty()) return out;
  std::string whole, element;
  for (const pipeline::SpringStiffness& s : f.springs) {
    const std::string at = s.setup.empty() ? "" : " at " + s.setup;
    whole += (whole.empty() ? "" : ", ") + Significant(s.per_spring_n_per_m / 1e6) + " N/µm" + at;
    if (std::isfinite(s.element_n_per_m))
      element += (element.empty() ? "" : ", ") + Significant(s.element_n_per_m / 1e6) + " N/µm" + at;
  }
  std::string springs = "per spring of '" + model::TargetText(f.effect.target) + "' now: " + whole;
  if (!element.empty()) springs += " (the element in series alone: " + element + ")";
  return out + (out.empty() ? "" : "; ") + springs;
}

std::string AgreementBasisWords(double sensor_mass_kg) {
  if (!(sensor_mass_kg > 0.0)) return "";
  return "Agreement / MAC: the model as stated against the test, without the test's own sensors (" +
         Significant(1e3 * sensor_mass_kg, 3) +
         " g per measured node), as a validation table compares them; the diagnosis carries the sensors, so its "
         "frequency errors are smaller.";
}

std::string ModelErrorLookAlikeWords(const pipeline::Findings& f) {
  if (!f.model_error_lookalike) return "";
  const pipeline::ModelErrorLookAlike& l = *f.model_error_lookalike;
  const diagnose::ModelError& e = f.model_error;  // rank 1's: what the model as given needs
  const bool shared = e.frequency_common_rel >= e.frequency_rel;
  const std::string size = Significant(100.0 * (shared ? e.frequency_common_rel : e.frequency_rel), 2) + " %";
  return ", but the next reading, " + l.description + " (" + Percent(l.probability) +
         "), brings the mean frequency error from " + FixedPoint(f.error_after_pct, 2) + " % to " +
         FixedPoint(l.error_after_pct, 2) + " %: these data cannot tell it from an error of the model's own (" +
         (shared ? size + " shared by all its frequencies" : "about " + size + " of each frequency") +
         "), and the priors order the two. If the model is known to be " +
         (shared ? "right overall (its stiffness-to-mass ratio) to better than " : "right mode by mode to better than ") +
         size + ", take that reading.";
}

}  // namespace ema::report
