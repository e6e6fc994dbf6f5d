#include "cli.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>

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

int NotBuiltYet(const std::string& command, const std::string& issue) {
  std::cerr << "ema " << command << ": not built yet (" << issue << ")\n";
  return 2;
}

bool StderrIsTerminal() { return isatty(fileno(stderr)) != 0; }

namespace {
struct Scope {
  bool active = false;
  double begin = 0.0, end = 1.0;
  std::string prefix;
};
Scope& CurrentScope() {
  static Scope scope;
  return scope;
}
}  // namespace

ProgressScope::ProgressScope(double begin, double end, std::string prefix) {
  CurrentScope() = Scope{true, begin, end, std::move(prefix)};
}

ProgressScope::~ProgressScope() { CurrentScope() = Scope{}; }

void DrawProgress(double fraction, const std::string& stage_in) {
  if (!StderrIsTerminal()) return;
  std::string stage = stage_in;
  if (const Scope& scope = CurrentScope(); scope.active) {
    fraction = scope.begin + (scope.end - scope.begin) * std::clamp(fraction, 0.0, 1.0);
    stage = scope.prefix + (stage.empty() ? std::string() : ": " + stage);
    if (fraction >= 1.0) fraction = std::nextafter(1.0, 0.0);  // the newline belongs to the whole run
  }
  constexpr int kWidth = 30;
  const int filled = static_cast<int>(fraction * kWidth + 0.5);
  std::string bar(filled, '#');
  bar.resize(kWidth, '.');
  std::fprintf(stderr, "\r[%s] %3d%% %-40.40s", bar.c_str(), static_cast<int>(fraction * 100 + 0.5), stage.c_str());
  if (fraction >= 1.0) std::fprintf(stderr, "\n");
  std::fflush(stderr);
}

}  // namespace ema::cli
