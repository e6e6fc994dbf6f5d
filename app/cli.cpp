#include "cli.hpp"

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <system_error>

#include "ema/core/error.hpp"

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

// The command-line option name as the user typed it ("output" -> "-o"/"--output").
std::string OptionLabel(const std::string& name, bool output) {
  if (name == "output") return "-o";
  if (output || name.find('-') != std::string::npos) return "--" + name;
  return name;  // positional inputs (file, input, model, ...)
}

}  // namespace

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
