// ema plan MODEL.toml [--setup NAME] [--band LO:HI] [--sensors N] [--sets N] [--triaxial]
//          [--references N] [--candidates DIAG.json] [--keep PLAN.toml] -o PLAN.toml [--json PLAN.json]
//
// The test to run next (docs/plan.md): sensors that see the band's modes distinctly, references
// that excite them all, acquisition settings from band and damping — and with --candidates the
// sensors that tell a diagnosis's look-alike readings apart. PLAN.toml is what `ema simulate`
// reads (docs/plan-format.md).
#include <filesystem>
#include <iostream>
#include <optional>

#include "cli.hpp"
#include "ema/core/error.hpp"
#include "ema/core/text.hpp"
#include "ema/formats/atomic_file.hpp"
#include "ema/formats/diagnosis_readings.hpp"
#include "ema/formats/model_file.hpp"
#include "ema/formats/plan_file.hpp"
#include "ema/formats/plan_json.hpp"
#include "ema/pipeline/run.hpp"
#include "stages.hpp"

namespace ema {
namespace {

std::string Percent(double share) { return FixedPoint(100.0 * share, 0) + " %"; }

}  // namespace

std::optional<app::PlanConfig> app::ParsePlanArgs(const std::vector<std::string>& args) {
  namespace po = cli::po;
  PlanConfig config;
  planning::PlanOptions& o = config.options;
  std::string band;
  po::options_description options("ema plan options");
  cli::AddHelp(&options);
  options.add_options()                                                                                       //
      ("model", po::value(&config.model_path)->required(), "model file (TOML)")                               //
      ("output,o", po::value(&config.output)->required(), "the plan (TOML, docs/plan-format.md)")             //
      ("json", po::value(&config.json_path), "the plan and its figures as JSON (cli.md)")                     //
      ("setup", po::value(&o.setup), "model setup the test is made in")                                       //
      ("band", po::value(&band), "LO:HI Hz: the modes the test must see (default: up to 1.25 x the 6th mode)")  //
      ("sensors", cli::Defaulted(&o.sensors_per_set), "sensors mounted at once (test points with --triaxial, else DOFs)")  //
      ("sets", cli::Defaulted(&o.sets), "roving sets (sensors x sets points or DOFs are measured)")           //
      ("triaxial", po::bool_switch(&o.triaxial), "each sensor measures X, Y and Z at one test point")        //
      ("references", cli::Defaulted(&o.references), "hammer DOFs")                                            //
      ("sensor-mass", cli::Defaulted(&o.sensor_mass_kg), "kg per sensor point, written to the plan")          //
      ("impacts", cli::Defaulted(&o.impacts), "impacts per reference and set")                                //
      ("candidates", po::value(&config.candidates_path), "DIAG.json: place sensors to tell rank 1 and its look-alikes apart")  //
      ("keep", po::value(&config.keep_path), "an earlier plan (TOML) to extend: its settings and sets stay, new sets are added");
  po::positional_options_description positional;
  positional.add("model", 1);
  po::variables_map vm;
  if (!cli::Parse(args,
                  "ema plan MODEL.toml [--setup NAME] [--band LO:HI] [--sensors N] [--sets N] [--triaxial]\n"
                  "         [--references N] [--candidates DIAG.json] [--keep PLAN.toml] -o PLAN.toml [--json PLAN.json]",
                  options, positional, &vm))
    return std::nullopt;
  if (!band.empty()) std::tie(o.band_lo_hz, o.band_hi_hz) = cli::ParseBand(band);
  if (std::string why; !o.IsValid(&why)) throw UsageError(why);
  cli::RefuseOutputsOverInputs(vm, {"model", "candidates", "keep"}, {"output", "json"});
  return config;
}

app::PlanStageResult app::RunPlanStage(const PlanConfig& config, const model::Model& model,
                                       const std::vector<planning::Reading>& readings,
                                       const std::optional<formats::Plan>& keep, std::ostream& out) {
  PlanStageResult result;
  std::vector<std::vector<Dof>> kept_sets;
  if (keep)
    for (const formats::RovingSet& s : keep->sets) kept_sets.push_back(s.sensors);
  planning::PlanOptions options = config.options;
  if (keep && options.setup.empty()) options.setup = keep->setup;  // the kept test's setup
  result.plan = planning::PlanTest(model, options, readings, kept_sets, keep ? keep->hammer.references : std::vector<Dof>{});
  if (keep) formats::AdoptKeptSettings(*keep, &result.plan);
  const planning::TestPlan& plan = result.plan;
  // The plan file: a kept plan's settings and sets stay as they were, new sets follow.
  result.file = formats::PlanFileOf(plan, keep, options.setup);
  const bool with_separations = !config.candidates_path.empty();
  result.json = formats::TestPlanJson(plan, with_separations);

  std::string comment = "Test plan of " + config.model_path + " made by `ema plan` (docs/plan.md).";
  if (keep) comment += "\nExtends " + config.keep_path + ": its settings and first " + std::to_string(kept_sets.size()) + " set(s) as they were.";
  if (with_separations) comment += "\nSensors placed to tell apart the look-alike readings of " + config.candidates_path + ".";
  formats::WritePlanFile(config.output, result.file, comment);
  if (!config.json_path.empty()) formats::WriteTextFileAtomically(config.json_path, result.json.dump(2) + "\n");

  // The screen: what the plan sees, how sure, what it could not do.
  out << "Plan: " << plan.Sensors().size() << " sensor DOFs in " << plan.sets.size() << " set(s), "
      << plan.references.size() << " reference(s), band " << FixedPoint(plan.band_lo_hz, 1) << "–"
      << FixedPoint(plan.band_hi_hz, 1) << " Hz (" << plan.modes.size() << " modes)\n";
  for (size_t s = 0; s < plan.sets.size(); ++s) {
    out << "  set " << s + 1 << ":";
    for (const Dof& d : plan.sets[s]) out << " " << DofName(d);
    out << "\n";
  }
  out << "  references:";
  for (const Dof& d : plan.references) out << " " << DofName(d);
  out << "\n  mode      f (Hz)  observability  excited by the references\n";
  auto right = [](const std::string& text, size_t width) { return std::string(width > text.size() ? width - text.size() : 0, ' ') + text; };
  for (size_t i = 0; i < plan.modes.size(); ++i) {
    const planning::PlannedMode& m = plan.modes[i];
    out << right(std::to_string(i + 1), 6) << right(FixedPoint(m.frequency_hz, 1), 12) << right(FixedPoint(m.observability, 2), 15)
        << right(Percent(m.reference_participation), 12) << (m.excited ? "" : "  (near a node line of every reference)") << "\n";
  }
  out << "  AutoMAC largest off-diagonal: " << FixedPoint(plan.automac_max_offdiagonal, 3) << "\n";
  out << "  Acquisition: " << FixedPoint(plan.sample_rate_hz, 0) << " Hz, " << plan.samples << " samples ("
      << FixedPoint(plan.samples / plan.sample_rate_hz, 2) << " s), hammer tip contact "
      << FixedPoint(1e3 * plan.pulse_duration_s, 2) << " ms, " << plan.impacts << " impacts per reference"
      << (keep ? " (kept plan's settings used)" : "") << "\n";
  if (with_separations) {
    if (plan.separations.empty())
      out << "  Look-alikes: " << config.candidates_path
          << " holds no reading within a factor 20 of rank 1: nothing to separate; the plan is for the modes\n";
    for (const planning::Separation& s : plan.separations)
      out << "  " << s.a << " vs " << s.b << ": " << FixedPoint(s.sigma_before, 1) << " σ → "
          << FixedPoint(s.sigma_after, 1) << " σ apart\n";
    if (!plan.separations.empty() && plan.separations_include_model_error)
      out << "  (σ: the test's noise and the model's own error the diagnosis inferred combined — "
          << FixedPoint(100.0 * plan.separation_frequency_sigma_rel, 2) << " % of each frequency, "
          << FixedPoint(100.0 * plan.separation_shape_sigma, 1)
          << " % of a shape's rms amplitude at each DOF: what a follow-up test must beat)\n";
  }
  for (const std::string& note : plan.notes) out << "  Note: " << note << ".\n";
  out << "wrote " << config.output << (config.json_path.empty() ? "" : " and " + config.json_path) << "\n";
  return result;
}

int RunPlan(const std::vector<std::string>& args) {
  std::optional<app::PlanConfig> config = app::ParsePlanArgs(args);
  if (!config) return 0;
  const model::Model model = formats::ReadModelFile(config->model_path);
  std::vector<planning::Reading> readings;
  if (!config->candidates_path.empty()) {
    std::error_code ec;
    if (!std::filesystem::exists(config->candidates_path, ec))
      throw InputError(config->candidates_path, "diagnosis file not found; expected the DIAG.json of `ema diagnose --json`");
    const std::filesystem::path path = config->candidates_path;
    const nlohmann::json diagnosis = formats::ReadDiagnosisJson(path);
    readings = formats::LookAlikeReadings(formats::ReadDiagnosisReadings(diagnosis, path.string(), path.parent_path()),
                                          config->candidates_path);
    pipeline::SeparateInModelError(formats::ReadDiagnosisModelError(diagnosis, path.string()), &config->options);
  }
  std::optional<formats::Plan> keep;
  if (!config->keep_path.empty()) {
    std::error_code ec;
    if (!std::filesystem::exists(config->keep_path, ec)) throw InputError(config->keep_path, "plan file not found");
    keep = formats::ReadPlanFile(config->keep_path);
  }
  app::RunPlanStage(*config, model, readings, keep, std::cout);
  return 0;
}

}  // namespace ema
