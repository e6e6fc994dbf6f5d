// ema correlate TEST_MODES.unv MODEL.toml|MODEL_MODES.unv [--setup NAME] [--json CORR.json]
//               [--table TABLE.md|TABLE.csv|TABLE.html]
// Test modes against model modes: shared DOFs, MAC, pairing, agreement, COMAC (cli.md, issue 5).
#include <filesystem>
#include <iostream>
#include <optional>
#include <nlohmann/json.hpp>

#include "cli.hpp"
#include "ema/core/error.hpp"
#include "ema/correlation/correlate.hpp"
#include "ema/formats/atomic_file.hpp"
#include "ema/formats/io.hpp"
#include "ema/formats/model_file.hpp"
#include "ema/formats/json_codecs.hpp"
#include "ema/model/solve.hpp"
#include "stages.hpp"

namespace ema {
namespace {

namespace fs = std::filesystem;

bool IsModelFile(const fs::path& path) {
  std::string ext = path.extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext == ".toml";
}

}  // namespace

std::optional<app::CorrelateConfig> app::ParseCorrelateArgs(const std::vector<std::string>& args) {
  namespace po = cli::po;
  const std::string usage =
      "ema correlate TEST_MODES.unv MODEL.toml|MODEL_MODES.unv [--setup NAME] [--json CORR.json] "
      "[--table TABLE.md|TABLE.csv|TABLE.html]";
  po::options_description options("options");
  CorrelateConfig config;
  correlation::CorrelationOptions& copt = config.options;
  options.add_options()("test", po::value(&config.test_path)->required(), "test modes (UFF 55)")(
      "model", po::value(&config.model_path)->required(), "model file (.toml) or model modes (UFF 55)")(
      "setup", po::value(&config.setup), "setup of the model file to solve (model files only)")(
      "json", po::value(&config.json_path), "write the correlation as JSON")(
      "table", po::value(&config.table_path), "write the validation table (.md, .csv or .html)")(
      "mac-min", po::value(&copt.pairing.mac_min)->default_value(copt.pairing.mac_min), "minimum MAC of a pair")(
      "tolerance", po::value(&copt.dofs.tolerance_m)->default_value(copt.dofs.tolerance_m),
      "match test nodes to the nearest model node within this distance [m] (0 = by node id only)")(
      "interface-damping", po::value(&copt.interface_damping_ratio)->default_value(copt.interface_damping_ratio),
      "test damping ratio above which a mode is remarked interface-dominated");
  cli::AddHelp(&options);
  po::positional_options_description positional;
  positional.add("test", 1).add("model", 1);
  po::variables_map vm;
  if (!cli::Parse(args, usage, options, positional, &vm)) return std::nullopt;
  cli::RefuseOutputsOverInputs(vm, {"test", "model"}, {"json", "table"});

  if (!config.table_path.empty()) {
    std::string ext = fs::path(config.table_path).extension().string();
    for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    if (!FromName(correlation::kTableFormatExtensions, ext, &config.table_format))
      throw UsageError("--table " + config.table_path + ": expected a .md, .csv or .html file name");
  }
  if (std::string why; !copt.IsValid(&why)) throw UsageError(why);
  if (!config.setup.empty() && !IsModelFile(config.model_path))
    throw UsageError("--setup applies to a model file (.toml), not to model modes " + config.model_path);
  return config;
}

correlation::CorrelationResult app::RunCorrelateStage(const CorrelateConfig& config, const ModeSet& test,
                                                      const ModeSet& model_modes, std::ostream& out) {
  const correlation::CorrelationResult result = correlation::Correlate(test, model_modes, config.options);
  WriteCorrelation(config, result, test, model_modes);
  PrintCorrelation(config, result, test, model_modes, out);
  return result;
}

void app::WriteCorrelation(const CorrelateConfig& config, const correlation::CorrelationResult& result, const ModeSet& test,
                           const ModeSet& model_modes) {
  if (!config.json_path.empty())
    formats::WriteTextFileAtomically(config.json_path, formats::CorrelationJson(result, test, model_modes).dump(2) + "\n");
  if (!config.table_path.empty())
    formats::WriteTextFileAtomically(config.table_path, correlation::FormatCorrelationTable(result, config.table_format));
}

void app::PrintCorrelation(const CorrelateConfig& config, const correlation::CorrelationResult& result, const ModeSet& test,
                           const ModeSet& model_modes, std::ostream& out) {
  // Positions matter only where nodes were paired by distance; say then when a file's length
  // unit was a guess (geometry in mm read as metres would pair nothing, or the wrong nodes).
  if (result.dof_match.nodes_by_distance > 0 || config.options.dofs.tolerance_m > 0.0)
    for (const ModeSet* set : {&test, &model_modes})
      if (!set->geometry_units_note.empty()) std::cerr << "warning: " << set->geometry_units_note << "\n";
  out << correlation::FormatCorrelationTable(result, correlation::TableFormat::kMarkdown);
}

int RunCorrelate(const std::vector<std::string>& args) {
  const std::optional<app::CorrelateConfig> config = app::ParseCorrelateArgs(args);
  if (!config) return 0;
  ModeSet test = formats::ReadModeSet(config->test_path);
  if (test.source.empty()) test.source = config->test_path;
  ModeSet model_modes;
  if (IsModelFile(config->model_path)) {
    const model::Model model = formats::ReadModelFile(config->model_path);
    model::SolveOptions solve_options;
    solve_options.setup = config->setup;
    model_modes = model::Solve(model, solve_options).modes;
  } else {
    model_modes = formats::ReadModeSet(config->model_path);
  }
  if (model_modes.source.empty()) model_modes.source = config->model_path;
  app::RunCorrelateStage(*config, test, model_modes, std::cout);
  return 0;
}

}  // namespace ema
