// Helpers shared by the subcommands of the `ema` CLI.
//
// Exit codes (cli.md): 0 success, 1 bad input (ema::InputError), 2 bad usage (ema::UsageError).
// Each subcommand is `int Run<Name>(const std::vector<std::string>& args)`, where args excludes
// the program and command names; main() catches everything.
#pragma once

#include <boost/program_options.hpp>
#include <iosfwd>
#include <string>
#include <vector>

namespace ema::cli {

namespace po = boost::program_options;

/// Parses `args` against `options` (+ positional), turning Boost's exceptions into UsageError.
/// Returns false when --help was given (after printing usage + options to stdout).
bool Parse(const std::vector<std::string>& args, const std::string& usage, const po::options_description& options,
           const po::positional_options_description& positional, po::variables_map* vm);

/// Adds the common --help switch to an options set.
void AddHelp(po::options_description* options);

/// A subcommand that is not built yet: prints so on stderr and returns exit code 2.
int NotBuiltYet(const std::string& command, const std::string& issue);

/// True when stderr is a terminal (progress bars are drawn only then).
bool StderrIsTerminal();

/// Draws/updates a one-line progress bar on stderr when it is a terminal; no-op otherwise.
void DrawProgress(double fraction, const std::string& stage);

}  // namespace ema::cli

namespace ema {
int RunInfo(const std::vector<std::string>& args);
int RunFrf(const std::vector<std::string>& args);
int RunFit(const std::vector<std::string>& args);
int RunModel(const std::vector<std::string>& args);
int RunCorrelate(const std::vector<std::string>& args);
int RunDiagnose(const std::vector<std::string>& args);
int RunRun(const std::vector<std::string>& args);
int RunSimulate(const std::vector<std::string>& args);
int RunQuality(const std::vector<std::string>& args);
int RunAmplitude(const std::vector<std::string>& args);
}  // namespace ema
