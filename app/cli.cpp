#include "cli.hpp"

#include <unistd.h>

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
