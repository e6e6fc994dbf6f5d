// ema model MODEL.toml [--setup NAME] -o MODEL_MODES.unv [--json MODEL_MODES.json] [--explain]
#include <iomanip>
#include <iostream>
#include <nlohmann/json.hpp>

#include "cli.hpp"
#include "ema/core/error.hpp"
#include "ema/formats/atomic_file.hpp"
#include "ema/formats/io.hpp"
#include "ema/formats/model_file.hpp"
#include "ema/model/solve.hpp"

namespace ema {

int RunModel(const std::vector<std::string>& args) {
  namespace po = cli::po;
  po::options_description options("ema model options");
  std::string model_path, out_path, json_path, setup;
  int max_modes = 0;
  cli::AddHelp(&options);
  options.add_options()                                                          //
      ("model", po::value(&model_path)->required(), "model file (TOML)")         //
      ("setup", po::value(&setup), "setup name (operating points by group)")     //
      ("output,o", po::value(&out_path)->required(), "mode shapes, UFF 55")      //
      ("json", po::value(&json_path), "modes as JSON (same layout as ema fit)")  //
      ("max-modes", po::value(&max_modes)->default_value(0), "elastic modes kept (0: all; sparse: 20)")  //
      ("binary", po::bool_switch(), "write binary UFF where the dataset allows it")                      //
      ("explain", po::bool_switch(), "print operating points, linearised stiffnesses, energy shares");
  po::positional_options_description positional;
  positional.add("model", 1);
  po::variables_map vm;
  const std::string usage =
      "ema model MODEL.toml [--setup NAME] -o MODEL_MODES.unv [--json MODEL_MODES.json] [--explain]";
  if (!cli::Parse(args, usage, options, positional, &vm)) return 0;
  cli::RefuseOutputsOverInputs(vm, {"model"}, {"output", "json"});
  if (max_modes < 0) throw UsageError("--max-modes must be >= 0");

  const model::Model m = formats::ReadModelFile(model_path);
  model::SolveOptions solve_options;
  solve_options.setup = setup;
  solve_options.max_modes = max_modes;
  const model::Solution sol = model::Solve(m, solve_options);
  for (const std::string& w : sol.warnings) std::cerr << "ema model: warning: " << w << "\n";
  if (m.points.empty())
    std::cerr << "ema model: warning: " << model_path << " has no [[point]]: mode shapes are written without DOFs\n";

  formats::WriteOptions write_options;
  write_options.binary = vm["binary"].as<bool>();
  formats::WriteModeSet(out_path, sol.modes, write_options);

  if (!json_path.empty()) {
    nlohmann::json j;
    j["model"] = m.name;
    j["setup"] = setup;
    j["modes"] = nlohmann::json::array();
    for (const Mode& mode : sol.modes.modes) {
      nlohmann::json jm{{"frequency_hz", mode.frequency_hz}, {"damping_ratio", mode.damping_ratio}, {"mpc", mode.mpc}};
      jm["shape"] = nlohmann::json::array();
      for (std::size_t i = 0; i < sol.modes.dofs.size(); ++i)
        jm["shape"].push_back({{"node", sol.modes.dofs[i].node},
                               {"dir", DirectionName(sol.modes.dofs[i].direction)},
                               {"value", {mode.shape[static_cast<int>(i)].real(), mode.shape[static_cast<int>(i)].imag()}}});
      j["modes"].push_back(jm);
    }
    j["rigid_body_frequencies_hz"] = sol.rigid_body_frequencies_hz;
    j["springs"] = nlohmann::json::array();
    for (const model::SpringState& s : sol.springs) {
      nlohmann::json js{{"name", s.name},         {"group", s.group},           {"law", s.law},
                        {"force_n", s.force},     {"deflection_m", s.deflection}, {"stiffness_n_per_m", s.stiffness}};
      if (!std::isnan(s.gap)) js["gap_m"] = s.gap;
      if (!s.element_deflections.empty()) {
        js["element_deflections_m"] = s.element_deflections;
        js["element_stiffnesses_n_per_m"] = s.element_stiffnesses;
      }
      j["springs"].push_back(js);
    }
    j["energy_share"] = nlohmann::json::array();
    for (const model::EnergyShare& e : sol.energy) j["energy_share"].push_back({{"body", e.body}, {"share", e.share}});
    formats::WriteTextFileAtomically(json_path, j.dump(2) + "\n");
  }

  std::cout << (m.name.empty() ? model_path : m.name) << (setup.empty() ? "" : " [" + setup + "]") << ": "
            << sol.modes.modes.size() << " modes" << (sol.sparse ? " (sparse solver)" : "") << ", "
            << sol.rigid_body_frequencies_hz.size() << " rigid-body modes\n";
  std::cout << std::fixed;
  for (std::size_t i = 0; i < sol.modes.modes.size(); ++i)
    std::cout << "  mode " << std::setw(2) << i + 1 << "  " << std::setprecision(2) << std::setw(10)
              << sol.modes.modes[i].frequency_hz << " Hz  damping " << std::setprecision(2)
              << 100.0 * sol.modes.modes[i].damping_ratio << " %\n";
  if (vm["explain"].as<bool>()) std::cout << model::Explain(sol);
  return 0;
}

}  // namespace ema
