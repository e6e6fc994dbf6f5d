// ema info FILE [--json OUT]: what a UFF or CSV time-data file holds (cli.md).
#include <iostream>
#include <optional>
#include <nlohmann/json.hpp>

#include "cli.hpp"
#include "ema/core/error.hpp"
#include "ema/core/types.hpp"
#include "ema/formats/atomic_file.hpp"
#include "ema/formats/info.hpp"
#include "ema/formats/json_codecs.hpp"
#include "stages.hpp"

namespace ema {

namespace {

nlohmann::json DofsJson(const std::set<std::pair<std::int64_t, int>>& dofs) {
  nlohmann::json out = nlohmann::json::array();
  for (const auto& [n, d] : dofs) out.push_back({{"node", n}, {"dir", formats::DirectionText(d)}});
  return out;
}

nlohmann::json ToJson(const formats::FileSummary& s) {
  nlohmann::json j;
  j["file"] = s.file;
  j["bytes"] = s.bytes;
  j["format"] = s.format;
  j["datasets"] = nlohmann::json::object();
  for (const auto& [n, c] : s.datasets) j["datasets"][std::to_string(n)] = c;
  j["binary_58"] = s.binary58;
  j["records"] = s.records;
  j["function_types"] = nlohmann::json::array();
  for (const auto& [t, c] : s.function_types) {
    nlohmann::json f{{"type", t}, {"name", formats::FunctionTypeName(t)}, {"count", c}};
    const auto it = s.abscissa.find(t);
    if (it != s.abscissa.end()) {
      const auto& a = it->second;
      if (std::isfinite(a.min)) {
        f["abscissa_min"] = a.min;
        f["abscissa_max"] = a.max;
      } else {
        f["abscissa_min"] = nullptr;
        f["abscissa_max"] = nullptr;
      }
      f["points_min"] = a.points_min;
      f["points_max"] = a.points_max;
      f["abscissa_units"] = std::vector<std::string>(a.units.begin(), a.units.end());
      f["ordinate_units"] = std::vector<std::string>(a.ordinate_units.begin(), a.ordinate_units.end());
    }
    j["function_types"].push_back(f);
  }
  j["response_dofs"] = DofsJson(s.response_dofs);
  j["reference_dofs"] = DofsJson(s.reference_dofs);
  std::set<std::string> dirs;
  std::set<std::int64_t> nodes(s.geometry_nodes.begin(), s.geometry_nodes.end());
  for (const auto& set : {s.response_dofs, s.reference_dofs})
    for (const auto& [n, d] : set) {
      dirs.insert(formats::DirectionText(d));
      nodes.insert(n);
    }
  nodes.insert(s.shape_nodes.begin(), s.shape_nodes.end());
  j["nodes"] = std::vector<std::int64_t>(nodes.begin(), nodes.end());
  j["directions"] = std::vector<std::string>(dirs.begin(), dirs.end());
  j["geometry_nodes"] = s.geometry_nodes.size();
  j["modes"] = s.modes;
  j["units"] = s.units;
  j["notes"] = s.notes;
  // The file name (as the shell gave it) and the labels: valid UTF-8 whatever bytes they hold.
  return formats::ValidUtf8(std::move(j));
}

}  // namespace

std::optional<app::InfoConfig> app::ParseInfoArgs(const std::vector<std::string>& args) {
  namespace po = cli::po;
  po::options_description options("ema info options");
  InfoConfig config;
  cli::AddHelp(&options);
  options.add_options()("file", po::value(&config.file)->required(), "UFF (.unv/.uff, 58b too) or CSV time-data file")(
      "json", po::value(&config.json_path), "also write the summary as JSON to this file");
  po::positional_options_description positional;
  positional.add("file", 1);
  po::variables_map vm;
  if (!cli::Parse(args, "ema info FILE [--json OUT]", options, positional, &vm)) return std::nullopt;
  cli::RefuseOutputsOverInputs(vm, {"file"}, {"json"});
  return config;
}

formats::FileSummary app::RunInfoStage(const InfoConfig& config, std::ostream& out) {
  const formats::FileSummary summary = formats::SummarizeFile(config.file);
  out << formats::SummaryText(summary);
  if (!config.json_path.empty()) formats::WriteTextFileAtomically(config.json_path, ToJson(summary).dump(2) + "\n");
  return summary;
}

int RunInfo(const std::vector<std::string>& args) {
  const std::optional<app::InfoConfig> config = app::ParseInfoArgs(args);
  if (!config) return 0;
  app::RunInfoStage(*config, std::cout);
  return 0;
}

}  // namespace ema
