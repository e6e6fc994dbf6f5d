// ema correlate TEST_MODES.unv MODEL.toml|MODEL_MODES.unv [--setup NAME] [--json CORR.json]
//               [--table TABLE.md|TABLE.csv|TABLE.html]
// Test modes against model modes: shared DOFs, MAC, pairing, agreement, COMAC (cli.md, issue 5).
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>

#include "cli.hpp"
#include "ema/core/error.hpp"
#include "ema/correlation/correlate.hpp"
#include "ema/formats/atomic_file.hpp"
#include "ema/formats/io.hpp"
#include "ema/formats/model_file.hpp"
#include "ema/model/solve.hpp"

namespace ema {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

bool IsModelFile(const fs::path& path) {
  std::string ext = path.extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext == ".toml";
}

// JSON numbers cannot be NaN: write null instead.
json Number(double value) { return std::isfinite(value) ? json(value) : json(nullptr); }

json CorrelationJson(const correlation::CorrelationResult& r, const ModeSet& test, const ModeSet& model) {
  json out;
  out["pairs"] = json::array();
  for (const auto& row : r.rows) {
    if (!row.paired()) continue;
    out["pairs"].push_back({{"test_mode", row.test_mode + 1},
                            {"model_mode", row.model_mode + 1},
                            {"test_frequency_hz", row.test_frequency_hz},
                            {"test_damping_ratio", Number(row.test_damping_ratio)},
                            {"model_frequency_hz", row.model_frequency_hz},
                            {"agreement_pct", row.agreement_pct},
                            {"frequency_error_pct", row.frequency_error_pct},
                            {"mac", row.mac},
                            {"remark", row.remark}});
  }
  out["unpaired_test"] = json::array();
  for (int i : r.pairing.unpaired_test)
    out["unpaired_test"].push_back({{"test_mode", i + 1},
                                    {"test_frequency_hz", test.modes[i].frequency_hz},
                                    {"test_damping_ratio", Number(test.modes[i].damping_ratio)}});
  out["unpaired_model"] = json::array();
  for (int j : r.pairing.unpaired_model)
    out["unpaired_model"].push_back({{"model_mode", j + 1}, {"model_frequency_hz", model.modes[j].frequency_hz}});
  out["summary"] = {{"mean_agreement_pct", Number(r.mean_agreement_pct)},
                    {"min_agreement_pct", Number(r.min_agreement_pct)},
                    {"mean_mac", Number(r.mean_mac)},
                    {"mean_abs_frequency_error_pct", Number(r.mean_abs_frequency_error_pct)},
                    {"shared_dofs", r.shared_dof_count},
                    {"test_dofs", r.test_dof_count},
                    {"paired", r.pairing.pairs.size()}};
  out["comac"] = json::array();
  for (const auto& c : r.comac)
    out["comac"].push_back({{"node", c.dof.node}, {"dir", DirectionName(c.dof.direction)}, {"comac", c.comac}});
  json mac = json::array();
  for (Eigen::Index i = 0; i < r.mac.rows(); ++i) {
    json row = json::array();
    for (Eigen::Index j = 0; j < r.mac.cols(); ++j) row.push_back(r.mac(i, j));
    mac.push_back(row);
  }
  out["mac"] = mac;  // rows: test modes, columns: model modes
  return out;
}

}  // namespace

int RunCorrelate(const std::vector<std::string>& args) {
  namespace po = cli::po;
  const std::string usage =
      "ema correlate TEST_MODES.unv MODEL.toml|MODEL_MODES.unv [--setup NAME] [--json CORR.json] "
      "[--table TABLE.md|TABLE.csv|TABLE.html]";
  po::options_description options("options");
  std::string test_path, model_path, setup, json_path, table_path;
  correlation::CorrelationOptions copt;
  options.add_options()("test", po::value(&test_path)->required(), "test modes (UFF 55)")(
      "model", po::value(&model_path)->required(), "model file (.toml) or model modes (UFF 55)")(
      "setup", po::value(&setup), "setup of the model file to solve (model files only)")(
      "json", po::value(&json_path), "write the correlation as JSON")(
      "table", po::value(&table_path), "write the validation table (.md, .csv or .html)")(
      "mac-min", po::value(&copt.pairing.mac_min)->default_value(0.6), "minimum MAC of a pair")(
      "tolerance", po::value(&copt.dofs.tolerance_m)->default_value(0.0),
      "match test nodes to the nearest model node within this distance [m] (0 = by node id only)")(
      "interface-damping", po::value(&copt.interface_damping_ratio)->default_value(0.01),
      "test damping ratio above which a mode is remarked interface-dominated");
  cli::AddHelp(&options);
  po::positional_options_description positional;
  positional.add("test", 1).add("model", 1);
  po::variables_map vm;
  if (!cli::Parse(args, usage, options, positional, &vm)) return 0;
  cli::RefuseOutputsOverInputs(vm, {"test", "model"}, {"json", "table"});

  correlation::TableFormat format = correlation::TableFormat::kMarkdown;
  if (!table_path.empty()) {
    std::string ext = fs::path(table_path).extension().string();
    for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    if (ext == ".csv") {
      format = correlation::TableFormat::kCsv;
    } else if (ext == ".html" || ext == ".htm") {
      format = correlation::TableFormat::kHtml;
    } else if (ext != ".md") {
      throw UsageError("--table " + table_path + ": expected a .md, .csv or .html file name");
    }
  }
  if (copt.pairing.mac_min < 0.0 || copt.pairing.mac_min > 1.0) throw UsageError("--mac-min must lie in [0, 1]");
  if (!setup.empty() && !IsModelFile(model_path))
    throw UsageError("--setup applies to a model file (.toml), not to model modes " + model_path);

  ModeSet test = formats::ReadModeSet(test_path);
  if (test.source.empty()) test.source = test_path;
  ModeSet model_modes;
  if (IsModelFile(model_path)) {
    const model::Model model = formats::ReadModelFile(model_path);
    model::SolveOptions sopt;
    sopt.setup = setup;
    model_modes = model::Solve(model, sopt).modes;
  } else {
    model_modes = formats::ReadModeSet(model_path);
  }
  if (model_modes.source.empty()) model_modes.source = model_path;

  const correlation::CorrelationResult result = correlation::Correlate(test, model_modes, copt);
  std::cout << correlation::FormatCorrelationTable(result, correlation::TableFormat::kMarkdown);
  if (!json_path.empty())
    formats::WriteTextFileAtomically(json_path, CorrelationJson(result, test, model_modes).dump(2) + "\n");
  if (!table_path.empty())
    formats::WriteTextFileAtomically(table_path, correlation::FormatCorrelationTable(result, format));
  return 0;
}

}  // namespace ema
