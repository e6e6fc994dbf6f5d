#include "cli.hpp"

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <system_error>

#include "ema/core/error.hpp"
#include "ema/formats/referenced_files.hpp"

namespace ema::cli {

void AddHelp(po::options_description* options) { options->add_options()("help,h", "show this help and exit"); }

bool Parse(const std::vector<std::string>& args, const std::string& usage, const po::options_description& options,
           const po::positional_options_description& positional, po::variables_map* vm) {
  try {
    po::store(po::command_line_parser(args).options(options).positional(positional).run(), *vm);
    if (vm->count("help")) {
      std::cout << "usage: " << usage << "\n\n" << options << "\n";
      return false;
    }
    po::notify(*vm);
  } catch (const po::error& e) {
    throw UsageError(std::string(e.what()) + "\nusage: " + usage + "\n(try --help)");
  }
  return true;
}

namespace {

namespace fs = std::filesystem;

// True when `a` and `b` name the same file: by identity when both exist (symlinks, hard links),
// else by their absolute paths with `.`, `..` and existing symlinks resolved.
bool SameFile(const fs::path& a, const fs::path& b) {
  std::error_code ec;
  if (fs::exists(a, ec) && fs::exists(b, ec)) {
    const bool same = fs::equivalent(a, b, ec);
    if (!ec) return same;
  }
  const fs::path ca = fs::weakly_canonical(fs::absolute(a, ec), ec);
  const fs::path cb = fs::weakly_canonical(fs::absolute(b, ec), ec);
  return ca == cb;
}

std::string Named(const PathArg& p) {
  const bool positional = p.option.empty() || p.option[0] != '-';
  return (positional ? std::string() : p.option + " ") + p.path;
}

// The command-line option name as the user typed it ("output" -> "-o"/"--output").
std::string OptionLabel(const std::string& name, bool output) {
  if (name == "output") return "-o";
  if (output || name.find('-') != std::string::npos) return "--" + name;
  return name;  // positional inputs (file, input, model, ...)
}

}  // namespace

void RefuseOutputsOverInputs(const std::vector<PathArg>& inputs, const std::vector<PathArg>& outputs) {
  // Expand the inputs: files named by TOML inputs, files in input folders.
  std::vector<std::pair<PathArg, fs::path>> all;  // (as given, the file)
  for (const PathArg& in : inputs) {
    if (in.path.empty()) continue;
    std::error_code ec;
    all.emplace_back(in, fs::path(in.path));
    if (fs::is_directory(in.path, ec)) {
      for (const auto& entry : fs::directory_iterator(in.path, ec))
        if (entry.is_regular_file(ec)) all.emplace_back(in, entry.path());
    } else if (fs::path(in.path).extension() == ".toml") {
      for (const fs::path& f : formats::FilesNamedIn(in.path)) all.emplace_back(in, f);
    }
  }
  for (std::size_t i = 0; i < outputs.size(); ++i) {
    const PathArg& out = outputs[i];
    if (out.path.empty()) continue;
    for (const auto& [in, file] : all) {
      if (!SameFile(out.path, file)) continue;
      // Built by append: GCC 12 warns (-Wrestrict, a false positive) on "literal" + std::string&&.
      std::string message = Named(out);
      message.append(": refused, it would replace ");
      if (file != fs::path(in.path)) message.append("'").append(file.string()).append("', which the input ");
      else message.append("the input ");
      message.append(Named(in));
      if (file != fs::path(in.path)) message.append(" names");
      message.append(" (outputs never replace inputs: choose another output name)");
      throw UsageError(message);
    }
    for (std::size_t j = 0; j < i; ++j)
      if (!outputs[j].path.empty() && SameFile(out.path, outputs[j].path))
        throw UsageError(Named(out) + ": refused, " + Named(outputs[j]) + " writes the same file");
  }
}

void RefuseOutputsOverInputs(const po::variables_map& vm, const std::vector<std::string>& input_options,
                             const std::vector<std::string>& output_options) {
  auto values = [&](const std::string& name) {
    std::vector<std::string> v;
    if (!vm.count(name)) return v;
    const boost::any& any = vm[name].value();
    if (const auto* s = boost::any_cast<std::string>(&any)) v.push_back(*s);
    else if (const auto* l = boost::any_cast<std::vector<std::string>>(&any)) v = *l;
    return v;
  };
  std::vector<PathArg> inputs, outputs;
  for (const std::string& name : input_options) {
    for (const std::string& value : values(name)) {
      inputs.push_back({OptionLabel(name, false), value});
      const auto eq = value.find('=');
      std::error_code ec;
      if (eq != std::string::npos && !fs::exists(value, ec)) inputs.push_back({OptionLabel(name, false), value.substr(eq + 1)});
    }
  }
  for (const std::string& name : output_options)
    for (const std::string& value : values(name)) outputs.push_back({OptionLabel(name, true), value});
  RefuseOutputsOverInputs(inputs, outputs);
}

double ParseNumber(const std::string& text, const std::string& option) {
  try {
    std::size_t used = 0;
    const double v = std::stod(text, &used);
    if (used == text.size() && std::isfinite(v)) return v;
  } catch (const std::exception&) {
  }
  throw UsageError(option + ": expected a number, got '" + text + "'");
}

std::pair<double, double> ParseBand(const std::string& text, const std::string& option) {
  const auto colon = text.find(':');
  if (colon == std::string::npos) throw UsageError(option + ": expected LO:HI in Hz, got '" + text + "'");
  const double lo = ParseNumber(text.substr(0, colon), option), hi = ParseNumber(text.substr(colon + 1), option);
  if (!(hi > lo) || lo < 0.0) throw UsageError(option + ": expected 0 <= LO < HI, got '" + text + "'");
  return {lo, hi};
}

int NotBuiltYet(const std::string& command, const std::string& issue) {
  std::cerr << "ema " << command << ": not built yet (" << issue << ")\n";
  return 2;
}

bool StderrIsTerminal() { return isatty(fileno(stderr)) != 0; }

void DrawProgress(double fraction, const std::string& stage) {
  if (!StderrIsTerminal()) return;
  constexpr int kWidth = 30;
  const int filled = static_cast<int>(fraction * kWidth + 0.5);
  std::string bar(filled, '#');
  bar.resize(kWidth, '.');
  std::fprintf(stderr, "\r[%s] %3d%% %-40.40s", bar.c_str(), static_cast<int>(fraction * 100 + 0.5), stage.c_str());
  if (fraction >= 1.0) std::fprintf(stderr, "\n");
  std::fflush(stderr);
}

}  // namespace ema::cli
