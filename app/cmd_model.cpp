// ema model MODEL.toml [--setup NAME] -o MODEL_MODES.unv [--json MODEL_MODES.json] [--explain]
#include <iomanip>
#include <iostream>
#include <optional>
#include <nlohmann/json.hpp>

#include "cli.hpp"
#include "ema/core/error.hpp"
#include "ema/formats/atomic_file.hpp"
#include "ema/formats/io.hpp"
#include "ema/formats/model_file.hpp"
#include "ema/formats/json_codecs.hpp"
#include "ema/model/solve.hpp"
#include "stages.hpp"

namespace ema {

std::optional<app::ModelConfig> app::ParseModelArgs(const std::vector<std::string>& args) {
  namespace po = cli::po;
  po::options_description options("ema model options");
  ModelConfig config;
  cli::AddHelp(&options);
  options.add_options()                                                                        //
      ("model", po::value(&config.model_path)->required(), "model file (TOML)")                //
      ("setup", po::value(&config.options.setup), "setup name (operating points by group)")    //
      ("output,o", po::value(&config.output)->required(), "mode shapes, UFF 55")               //
      ("json", po::value(&config.json_path), "modes as JSON (same layout as ema fit)")         //
      ("max-modes", po::value(&config.options.max_modes)->default_value(config.options.max_modes),
       "elastic modes kept (0: all; sparse: 20)")                                              //
      ("binary", po::bool_switch(&config.binary), "write binary UFF where the dataset allows it")  //
      ("explain", po::bool_switch(&config.explain), "print operating points, linearised stiffnesses, energy shares");
  po::positional_options_description positional;
  positional.add("model", 1);
  po::variables_map vm;
  const std::string usage =
      "ema model MODEL.toml [--setup NAME] -o MODEL_MODES.unv [--json MODEL_MODES.json] [--explain]";
  if (!cli::Parse(args, usage, options, positional, &vm)) return std::nullopt;
  cli::RefuseOutputsOverInputs(vm, {"model"}, {"output", "json"});
  if (std::string why; !config.options.IsValid(&why)) throw UsageError(why);
  return config;
}

model::Solution app::RunModelStage(const ModelConfig& config, const model::Model& m, std::ostream& out) {
  const model::Solution solution = model::Solve(m, config.options);
  WriteModel(config, m, solution);
  PrintModel(config, m, solution, out);
  return solution;
}

void app::WriteModel(const ModelConfig& config, const model::Model& m, const model::Solution& solution) {
  const nlohmann::json json = formats::ModelSolutionJson(m, solution, config.options.setup);
  formats::WriteOptions write_options;
  write_options.binary = config.binary;
  formats::WriteModeSet(config.output, solution.modes, write_options);
  if (!config.json_path.empty()) formats::WriteTextFileAtomically(config.json_path, json.dump(2) + "\n");
}

void app::PrintModel(const ModelConfig& config, const model::Model& m, const model::Solution& sol, std::ostream& out) {
  const std::string& setup = config.options.setup;
  for (const std::string& w : sol.warnings) std::cerr << "ema model: warning: " << w << "\n";
  if (m.points.empty())
    std::cerr << "ema model: warning: " << config.model_path << " has no [[point]]: mode shapes are written without DOFs\n";
  out << (m.name.empty() ? config.model_path : m.name) << (setup.empty() ? "" : " [" + setup + "]") << ": "
      << sol.modes.modes.size() << " modes" << (sol.sparse ? " (sparse solver)" : "") << ", "
      << sol.rigid_body_frequencies_hz.size() << " rigid-body modes\n";
  const auto flags = out.flags();
  const auto precision = out.precision();
  out << std::fixed;
  for (std::size_t i = 0; i < sol.modes.modes.size(); ++i)
    out << "  mode " << std::setw(2) << i + 1 << "  " << std::setprecision(2) << std::setw(10)
        << sol.modes.modes[i].frequency_hz << " Hz  damping " << std::setprecision(2)
        << 100.0 * sol.modes.modes[i].damping_ratio << " %\n";
  if (config.explain) out << model::Explain(sol);
  out.flags(flags);
  out.precision(precision);
}

int RunModel(const std::vector<std::string>& args) {
  const std::optional<app::ModelConfig> config = app::ParseModelArgs(args);
  if (!config) return 0;
  app::RunModelStage(*config, formats::ReadModelFile(config->model_path), std::cout);
  return 0;
}

}  // namespace ema
