// ema simulate MODEL.toml --plan PLAN.toml -o TIME.unv [--setup NAME] [--binary]
//
// A roving hammer test of the model (docs/plan-format.md; the stage is pipeline::SimulateTest):
// per roving set the model is solved with that set's sensor masses mounted, its modes become the
// acquisition simulator's modal truth, and the records of every set are written as UFF 58 time data.
#include <filesystem>
#include <iostream>
#include <optional>
#include <sstream>

#include "cli.hpp"
#include "ema/core/error.hpp"
#include "ema/formats/io.hpp"
#include "ema/formats/model_file.hpp"
#include "ema/formats/plan_file.hpp"
#include "ema/pipeline/stages.hpp"
#include "stages.hpp"

namespace ema {

std::string app::SimulateSummary(const pipeline::SimulateStage& stage) {
  std::ostringstream out;
  if (stage.in_time)
    out << "simulated " << stage.records.size() << " records in time (" << stage.nonlinear_elements
        << " non-linear element(s)): " << stage.sets << " roving set(s), " << stage.references << " reference(s), "
        << stage.impacts_per_reference << " impacts each at " << stage.force_levels << " force level(s)";
  else
    out << "simulated " << stage.records.size() << " records: " << stage.sets << " roving set(s), " << stage.references
        << " reference(s), " << stage.impacts_per_reference << " impacts each"
        << (stage.force_levels == 0 ? "" : " per force level") << ", " << stage.modes << " modes";
  return out.str();
}

std::optional<app::SimulateConfig> app::ParseSimulateArgs(const std::vector<std::string>& args) {
  namespace po = cli::po;
  po::options_description options("ema simulate options");
  SimulateConfig config;
  cli::AddHelp(&options);
  options.add_options()                                                                          //
      ("model", po::value(&config.model_path)->required(), "model file (TOML)")                  //
      ("plan", po::value(&config.plan_path)->required(), "test plan (TOML, docs/plan-format.md)")  //
      ("output,o", po::value(&config.output)->required(), "time data, UFF 58")                  //
      ("setup", po::value(&config.setup), "model setup (overrides the plan's setup)")           //
      ("binary", po::bool_switch(&config.binary), "write UFF 58b (binary)");
  po::positional_options_description positional;
  positional.add("model", 1);
  po::variables_map vm;
  if (!cli::Parse(args, "ema simulate MODEL.toml --plan PLAN.toml -o TIME.unv [--setup NAME] [--binary]", options,
                  positional, &vm))
    return std::nullopt;
  cli::RefuseOutputsOverInputs(vm, {"model", "plan"}, {"output"});
  return config;
}

std::vector<TimeRecord> app::RunSimulateStage(const SimulateConfig& config, const model::Model& m, formats::Plan plan,
                                              std::ostream& out) {
  if (!config.setup.empty()) plan.setup = config.setup;
  const pipeline::SimulateStage stage =
      pipeline::SimulateTest(m, plan, config.model_path, config.plan_path,
                             [](double fraction, std::string_view step) { cli::DrawProgress(fraction, std::string(step)); });
  if (stage.undamped) std::cerr << "ema simulate: warning: undamped modes (set [damping] in the model); records will not decay\n";
  formats::WriteOptions wo;
  wo.binary = config.binary;
  formats::WriteTimeRecords(config.output, stage.records, wo);
  out << SimulateSummary(stage) << "\n";
  return stage.records;
}

int RunSimulate(const std::vector<std::string>& args) {
  const std::optional<app::SimulateConfig> config = app::ParseSimulateArgs(args);
  if (!config) return 0;
  const model::Model model = formats::ReadModelFile(config->model_path);
  std::error_code exists_ec;
  if (!std::filesystem::exists(config->plan_path, exists_ec)) throw InputError(config->plan_path, "plan file not found");
  app::RunSimulateStage(*config, model, formats::ReadPlanFile(config->plan_path), std::cout);
  return 0;
}

}  // namespace ema
