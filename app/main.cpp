// ema: experimental modal analysis from the command line. See `ema --help` and ../shared/spec/cli.md.
#include <exception>
#include <iostream>
#include <string>
#include <vector>

#include "cli.hpp"
#include "ema/core/error.hpp"

namespace {

struct Command {
  const char* name;
  int (*run)(const std::vector<std::string>&);
  const char* summary;
};

const Command kCommands[] = {
    {"info", ema::RunInfo, "what a UFF/CSV file holds: datasets, records, nodes, ranges"},
    {"frf", ema::RunFrf, "hammer time data -> H1/H2/Hv FRFs with coherence"},
    {"quality", ema::RunQuality, "data-quality checks: reciprocity, driving points, coherence, scatter, MPC/MPD/MCF"},
    {"fit", ema::RunFit, "FRFs -> poles (PolyMAX), stabilisation diagram, mode shapes (LSFD)"},
    {"pick", ema::RunPick, "pick poles by hand on the stabilisation diagram in the browser (ema fit --select)"},
    {"fe-import", ema::RunFeImport, "FE parts from the FE code's matrix files (CalculiX, Abaqus) -> [fe] model, sparse"},
    {"model", ema::RunModel, "a spatial model's own modes (and --explain its operating point)"},
    {"correlate", ema::RunCorrelate, "test modes against model modes: MAC, pairing, validation table"},
    {"diagnose", ema::RunDiagnose, "rank the physical effects the model is missing"},
    {"run", ema::RunRun, "the whole story from a project file, with an HTML report"},
    {"plan", ema::RunPlan, "the test to run next: sensors, references, settings; --candidates: to tell readings apart"},
    {"simulate", ema::RunSimulate, "a roving hammer test of a model, as UFF 58 time data"},
    {"amplitude", ema::RunAmplitude, "does a mode depend on the excitation level? f and damping vs level"},
};

void PrintUsage(std::ostream& out) {
  out << "usage: ema <command> [options]   (ema <command> --help for its options)\n\ncommands:\n";
  for (const auto& c : kCommands) out << "  " << c.name << std::string(11 - std::string(c.name).size(), ' ') << c.summary << "\n";
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> args(argv + 1, argv + argc);
  if (args.empty()) {
    PrintUsage(std::cerr);
    return 2;
  }
  const std::string name = args.front();
  if (name == "--help" || name == "-h" || name == "help") {
    PrintUsage(std::cout);
    return 0;
  }
  if (name == "--version") {
    std::cout << "ema 0.1.0\n";
    return 0;
  }
  args.erase(args.begin());
  for (const auto& c : kCommands) {
    if (name != c.name) continue;
    try {
      return c.run(args);
    } catch (const ema::UsageError& e) {
      std::cerr << "ema " << name << ": " << e.what() << "\n";
      return 2;
    } catch (const ema::InputError& e) {
      std::cerr << "ema " << name << ": error: " << e.what() << "\n";
      return 1;
    } catch (const ema::ConvergenceError& e) {
      std::cerr << "ema " << name << ": error: did not converge: " << e.what() << "\n";
      return 3;
    } catch (const std::bad_alloc&) {
      std::cerr << "ema " << name << ": error: out of memory\n";
      return 1;
    } catch (const std::exception& e) {
      std::cerr << "ema " << name << ": error: " << e.what() << "\n";
      return 1;
    } catch (...) {
      std::cerr << "ema " << name << ": error: unknown failure\n";
      return 1;
    }
  }
  std::cerr << "ema: unknown command '" << name << "'\n";
  PrintUsage(std::cerr);
  return 2;
}
