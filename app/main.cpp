// ema: experimental modal analysis from the command line. See `ema --help` and ../shared/spec/cli.md.
#include <malloc.h>
#include <unistd.h>

#include <cstdlib>
#include <exception>
#include <iostream>
#include <string>
#include <strings.h>
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

// OpenBLAS's name for the kernels it chose at load time (weak: null where the BLAS is another).
extern "C" char* openblas_get_corename(void) __attribute__((weak));

// OpenBLAS picks its kernels by CPU model when it loads and falls back to its generic "Prescott"
// (SSE3) ones on a CPU newer than it knows: Debian 12's 0.3.21 on Emerald Rapids (model 207) runs
// CHOLMOD's supernodal factorisation and block solves ~1.4× slower than with the AVX-512 kernels
// the CPU has (one 220 941-DOF eigen-solution 81 → 59 s, docs/model.md). The choice can only be
// made before the library loads (OPENBLAS_CORETYPE), so ema starts itself again with it set when
// the fallback was taken and the CPU has the instructions of a kernel set OpenBLAS does know. A
// user's own OPENBLAS_CORETYPE is left alone (and ends the loop: the second start has it set).
void UseTheCpusBlasKernels(char** argv) {
  if (!openblas_get_corename || std::getenv("OPENBLAS_CORETYPE")) return;
  const char* core = openblas_get_corename();
  if (!core || strcasecmp(core, "prescott") != 0) return;
  __builtin_cpu_init();
  const char* better = nullptr;
  if (__builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512dq") && __builtin_cpu_supports("avx512cd") &&
      __builtin_cpu_supports("avx512bw") && __builtin_cpu_supports("avx512vl"))
    better = "SkylakeX";
  else if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma"))
    better = "Haswell";
  // The program's own path (not /proc/self/exe itself, which `ps` would then name "exe").
  char self[4096];
  const ssize_t length = readlink("/proc/self/exe", self, sizeof self - 1);
  if (!better || length <= 0 || setenv("OPENBLAS_CORETYPE", better, 1) != 0) return;
  self[length] = '\0';
  execv(self, argv);
  unsetenv("OPENBLAS_CORETYPE");  // not started again: go on with the kernels loaded
}

// The FE numerics allocate and free blocks of tens of MB to GBs over and over: 30 vectors of a
// 220 941-DOF model are 53 MB, a factorisation several GB. glibc serves every block above its mmap
// threshold (at most 32 MB) by a fresh mmap and unmaps it on free, so each reuse has the kernel zero
// the pages again — 31 M page faults in one diagnosis of that model, the kernel's page clearing 6 %
// of its CPU. With mmap off and the heap never trimmed, freed blocks are reused: 4.1 M page faults,
// 9 min 40 s → 7 min 10 s on an otherwise equal tree, peak 14.9 → 16.3 GB (docs/model.md). The
// process ends when its command does, so the memory kept is never wanted back; the Python module,
// a long-lived process, keeps glibc's defaults.
void ReuseFreedMemory() {
  mallopt(M_MMAP_MAX, 0);
  mallopt(M_TRIM_THRESHOLD, -1);  // read as the largest size_t: never trim
}

}  // namespace

int main(int argc, char** argv) {
  UseTheCpusBlasKernels(argv);
  ReuseFreedMemory();
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
