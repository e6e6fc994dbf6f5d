// Helpers shared by the subcommands of the `ema` CLI.
//
// Exit codes (cli.md, docs/cli.md): 0 success, 1 bad input (ema::InputError), 2 bad usage
// (ema::UsageError), 3 a solver did not converge (ema::ConvergenceError).
// Each subcommand is `int Run<Name>(const std::vector<std::string>& args)`, where args excludes
// the program and command names; main() catches everything.
#pragma once

#include <boost/program_options.hpp>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "ema/formats/output_guard.hpp"

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

/// A path a command reads or writes, with the option that named it (for messages).
using PathArg = formats::PathArg;

/// cli.md "Every command: outputs never replace inputs" (formats/output_guard.hpp): UsageError
/// (exit 2) naming both paths when an output resolves to one of the inputs, or two outputs to one
/// file. Call at the top of a command, before anything is read or written.
using formats::RefuseOutputsOverInputs;

/// The same, with the paths taken from the parsed options: the values (string or list of
/// strings) of `input_options` and `output_options` that were given; a `NAME=PATH` input value
/// (`ema diagnose --test SETUP=MODES.unv`) counts as PATH when NAME=PATH is not itself a file.
void RefuseOutputsOverInputs(const po::variables_map& vm, const std::vector<std::string>& input_options,
                             const std::vector<std::string>& output_options);

/// An option bound to `*field` whose default is the value the field holds (the options struct is
/// the single source of defaults; --help shows it as "%g" prints it).
template <class T>
po::typed_value<T>* Defaulted(T* field) {
  std::ostringstream text;
  text << *field;
  return po::value(field)->default_value(*field, text.str());
}

/// A finite number given to `option`; UsageError "OPTION: expected a number, got 'TEXT'".
double ParseNumber(const std::string& text, const std::string& option);

/// `--band LO:HI` in Hz with 0 <= LO < HI; UsageError naming `option` otherwise.
std::pair<double, double> ParseBand(const std::string& text, const std::string& option = "--band");

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
int RunPick(const std::vector<std::string>& args);
int RunPlan(const std::vector<std::string>& args);
int RunFeImport(const std::vector<std::string>& args);
}  // namespace ema
