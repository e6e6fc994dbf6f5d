// ema fe-import --nominal RUN --part NAME=RUN[:SCALE] ... -o FE.toml   (docs/fe-parts.md, docs/cli.md)
//
// The FE parts of a model, imported sparse from what the FE code wrote: the nominal run's matrices
// and, per part, a run with that part's modulus scaled (the difference of two assemblies) or the
// part's own matrix (Abaqus *MATRIX GENERATE, ELSET=). Writes the [fe] + [[fe.part]] TOML and its
// Matrix Market files beside it (formats/fe_import.hpp).
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "cli.hpp"
#include "ema/core/error.hpp"
#include "ema/formats/fe_import.hpp"

namespace ema {

namespace {

namespace fs = std::filesystem;

struct FeImportConfig {
  std::string nominal;
  std::vector<std::string> parts, part_matrices;
  std::string output;
  double scale = 0.5;
  std::string group, nodes, deck;
  std::optional<double> uncertainty;
  formats::FeImportOptions options;
};

std::string OffText(double relative) {
  char text[64];
  std::snprintf(text, sizeof text, "; off its elements %.1e of max |K|", relative);
  return text;
}

bool PartNameOk(const std::string& name) {
  if (name.empty() || name == "rest") return false;
  for (const char c : name)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.')) return false;
  return true;
}

// NAME=RUN[:SCALE]; the scale is what follows the last ':' when that reads as a number.
formats::FePartInput ParsePart(const std::string& text, double default_scale, bool direct, const std::string& option) {
  const auto eq = text.find('=');
  if (eq == std::string::npos || eq == 0 || eq + 1 == text.size())
    throw UsageError(option + ": expected NAME=" + (direct ? "FILE.mtx" : "RUN[:SCALE]") + ", got '" + text + "'");
  formats::FePartInput part;
  part.name = text.substr(0, eq);
  if (!PartNameOk(part.name))
    throw UsageError(option + ": part name '" + part.name +
                     "': use letters, digits, '_', '-' and '.' (it names the file K_NAME.mtx; 'rest' is taken)");
  std::string run = text.substr(eq + 1);
  part.scale = default_scale;
  part.direct = direct;
  if (!direct) {
    const auto colon = run.rfind(':');
    if (colon != std::string::npos) {
      part.scale = cli::ParseNumber(run.substr(colon + 1), option + " " + part.name);
      run = run.substr(0, colon);
    }
    if (!(part.scale > 0.0) || part.scale == 1.0)
      throw UsageError(option + " " + part.name + ": the scale must be positive and not 1, got " + std::to_string(part.scale));
  }
  part.run = formats::FeRunNamed(run);
  if (direct && part.run.code != formats::FeRun::Code::kAbaqus)
    throw UsageError(option + " " + part.name + ": expected an Abaqus matrix file (.mtx), got '" + run + "'");
  return part;
}

std::optional<FeImportConfig> ParseFeImportArgs(const std::vector<std::string>& args) {
  namespace po = cli::po;
  FeImportConfig config;
  po::options_description options("ema fe-import options");
  cli::AddHelp(&options);
  double uncertainty = 0.0;
  options.add_options()  //
      ("nominal", po::value(&config.nominal)->required(),
       "the nominal run: a CalculiX job (JOB, JOB.sti or JOB.inp: JOB.sti, JOB.mas, JOB.dof of "
       "*FREQUENCY, SOLVER=MATRIXSTORAGE) or an Abaqus stiffness file X_STIF1.mtx (FORMAT=MATRIX INPUT; its "
       "mass X_MASS1.mtx when present)")  //
      ("part", po::value(&config.parts)->composing(),
       "NAME=RUN[:SCALE], repeated: a run with part NAME's modulus x SCALE (default --scale); "
       "K_NAME = (K_nominal - K_RUN) / (1 - SCALE)")  //
      ("part-matrix", po::value(&config.part_matrices)->composing(),
       "NAME=FILE.mtx, repeated: part NAME's own stiffness (Abaqus *MATRIX GENERATE, ELSET=), on the "
       "nominal run's DOFs")  //
      ("output,o", po::value(&config.output)->required(),
       "the model TOML to write ([fe] + [[fe.part]]); M.mtx, K_rest.mtx, K_NAME.mtx and dofs.csv are "
       "written beside it")  //
      ("scale", cli::Defaulted(&config.scale), "the modulus factor of the parts' runs (0.5: exact in binary)")  //
      ("group", po::value(&config.group), "the parts' group (e.g. joints: targets joints and joints/NAME)")  //
      ("uncertainty", po::value(&uncertainty), "the parts' prior, relative 1 sigma (default: none written)")  //
      ("nodes", po::value(&config.nodes), "[fe] nodes: the node file as the TOML should name it (nodes.csv, UFF)")  //
      ("deck", po::value(&config.deck),
       "the nominal input deck (.inp, CalculiX or Abaqus): its *ELEMENT/*ELSET sets, one named as each part; "
       "checks that each part lies on its own elements' DOFs and K_rest on the other elements'")  //
      ("part-tolerance", cli::Defaulted(&config.options.part_tolerance),
       "with --deck: a part's entries off its elements, up to this x max|K_nominal|, are round-off (zeroed); "
       "more is an error")  //
      ("rest-tolerance", cli::Defaulted(&config.options.rest_tolerance),
       "K_rest's entries where only parts have elements, up to this x max|K_nominal|, are round-off (zeroed); "
       "with --deck more is an error")  //
      ("psd-tolerance", cli::Defaulted(&config.options.psd_tolerance),
       "a part is positive semi-definite when K_part + tau*I factorises, tau = this x its largest diagonal")  //
      ("symmetry-tolerance", cli::Defaulted(&config.options.symmetry_tolerance),
       "a matrix given in full (both triangles): |A_ij - A_ji| allowed, relative to its largest entry");
  po::positional_options_description positional;
  po::variables_map vm;
  const std::string usage =
      "ema fe-import --nominal RUN --part NAME=RUN[:SCALE] [--part ...] [--part-matrix NAME=FILE.mtx ...] -o FE.toml "
      "[--deck NOMINAL.inp] [--group G] [--uncertainty U] [--nodes nodes.csv]";
  if (!cli::Parse(args, usage, options, positional, &vm)) return std::nullopt;
  if (vm.count("uncertainty")) {
    if (!(uncertainty > 0.0)) throw UsageError("--uncertainty must be > 0");
    config.uncertainty = uncertainty;
  }
  if (!(config.scale > 0.0) || config.scale == 1.0) throw UsageError("--scale must be positive and not 1");
  if (std::string why; !config.options.IsValid(&why)) throw UsageError(why);
  if (config.parts.empty() && config.part_matrices.empty())
    throw UsageError("no part: give --part NAME=RUN[:SCALE] (or --part-matrix NAME=FILE.mtx) at least once\nusage: " + usage);
  if (fs::path(config.output).extension() != ".toml")
    throw UsageError("-o: expected the model TOML to write (FE.toml), got '" + config.output + "'");
  return config;
}

int RunFeImportImpl(const FeImportConfig& config) {
  const auto t0 = std::chrono::steady_clock::now();
  const formats::FeRun nominal = formats::FeRunNamed(config.nominal);
  std::vector<formats::FePartInput> parts;
  std::set<std::string> names;
  for (const std::string& p : config.parts) parts.push_back(ParsePart(p, config.scale, false, "--part"));
  for (const std::string& p : config.part_matrices) parts.push_back(ParsePart(p, config.scale, true, "--part-matrix"));
  for (const auto& p : parts)
    if (!names.insert(p.name).second) throw UsageError("part '" + p.name + "' given twice");
  // Outputs never replace inputs (cli.md): every file read, every file written.
  std::vector<cli::PathArg> inputs, outputs;
  const auto add_run = [&](const std::string& option, const formats::FeRun& run) {
    for (const fs::path& p : {run.stiffness, run.mass, run.dofs})
      if (!p.empty()) inputs.push_back({option, p.string()});
  };
  add_run("--nominal", nominal);
  if (!config.deck.empty()) inputs.push_back({"--deck", config.deck});
  for (const auto& p : parts) add_run(p.direct ? "--part-matrix" : "--part", p.run);
  const fs::path toml(config.output);
  const fs::path dir = toml.parent_path();
  outputs.push_back({"-o", toml.string()});
  for (const std::string name : {"M.mtx", "K_rest.mtx", "dofs.csv"}) outputs.push_back({"-o", (dir / name).string()});
  for (const auto& p : parts) outputs.push_back({"-o", (dir / ("K_" + p.name + ".mtx")).string()});
  cli::RefuseOutputsOverInputs(inputs, outputs);
  std::error_code ec;
  if (!dir.empty() && !fs::is_directory(dir, ec)) throw InputError(dir.string(), "-o: no such folder");

  std::optional<formats::FeElementSets> elements;
  if (!config.deck.empty()) elements = formats::ReadInpElementSets(config.deck);
  const formats::FeImport imported = formats::ImportFeParts(
      nominal, parts, config.options, [](double f, std::string_view s) { cli::DrawProgress(f, std::string(s)); },
      elements ? &*elements : nullptr);
  formats::FeImportWriteOptions write;
  write.group = config.group;
  write.uncertainty = config.uncertainty;
  write.nodes = config.nodes;
  write.comment = "FE parts imported by ema fe-import from " + config.nominal + " (" +
                  std::to_string(parts.size()) + " parts; docs/fe-parts.md)";
  formats::WriteFeImport(imported, toml, write);

  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("%zu DOFs; K_rest %ld entries (lower triangle), M %ld; max |K| %.6g\n", imported.dofs.size(),
              static_cast<long>(imported.rest.nonZeros()), static_cast<long>(imported.mass.nonZeros()),
              imported.max_stiffness);
  for (const auto& p : imported.parts)
    std::printf("  part %-12s %7ld DOFs, %9ld entries, PSD; %s%s\n", p.name.c_str(), static_cast<long>(p.dof_count),
                static_cast<long>(p.stiffness.nonZeros()),
                p.direct ? "own matrix" : ("difference, scale " + std::to_string(p.scale).substr(0, 6)).c_str(),
                elements ? OffText(p.largest_dropped).c_str() : "");
  std::printf("checks: DOF maps identical, matrices symmetric, parts positive semi-definite, not overlapping%s; "
              "K_rest round-off dropped up to %.1e of max |K|\n",
              elements ? ", on their own elements" : "", imported.rest_largest_dropped);
  std::printf("wrote %s (%.1f s)\n", toml.string().c_str(), seconds);
  return 0;
}

}  // namespace

int RunFeImport(const std::vector<std::string>& args) {
  const std::optional<FeImportConfig> config = ParseFeImportArgs(args);
  if (!config) return 0;
  return RunFeImportImpl(*config);
}

}  // namespace ema
