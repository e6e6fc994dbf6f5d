// ML refinement (issue 18) on the case: 144 FRFs (48 responses × 3 references) × 4000 lines,
// 7 modes 110-440 Hz with zeta 0.1-5 % (the 3 %-damped mode at 440 Hz, 12 % below the 500 Hz band
// edge), 1 % and 5 % noise. Counters: the PolyMAX stage's time and the refinement's, and the worst
// relative errors of f and zeta against the truth, without and with the refinement.
//
// `bench_ml_refine --write-gvt FILE.unv` writes the ground-vibration-test size set instead
// (1000 responses × 3 references × 4000 lines, same 7 modes, 1 % noise, ASCII UFF 58) for the
// `/usr/bin/time -v ema fit` measurement in docs/performance.md.
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstring>
#include <iostream>

#include "../tests/curvefit/synthetic.hpp"
#include "ema/curvefit/fit.hpp"
#include "ema/formats/io.hpp"

namespace {

using ema::curvefit::test::MakeFrfSet;
using ema::curvefit::test::MakeTruth;
using ema::curvefit::test::Truth;

const std::vector<double> kF = {110.0, 160.0, 205.0, 262.0, 318.0, 371.0, 440.0};
const std::vector<double> kZ = {0.001, 0.005, 0.01, 0.02, 0.05, 0.015, 0.03};

std::vector<int> Refs(int n_dofs) { return {n_dofs / 7, n_dofs / 2, (6 * n_dofs) / 7}; }

void WorstErrors(const ema::ModeSet& modes, double* df, double* dz, int* found) {
  *df = *dz = 0.0;
  *found = 0;
  for (size_t r = 0; r < kF.size(); ++r) {
    const ema::Mode* best = nullptr;
    for (const auto& m : modes.modes)
      if (std::abs(m.frequency_hz - kF[r]) < 0.02 * kF[r] &&
          (!best || std::abs(m.frequency_hz - kF[r]) < std::abs(best->frequency_hz - kF[r])))
        best = &m;
    if (!best) continue;
    ++*found;
    *df = std::max(*df, std::abs(best->frequency_hz / kF[r] - 1.0));
    *dz = std::max(*dz, std::abs(best->damping_ratio / kZ[r] - 1.0));
  }
}

void BM_Fit144(benchmark::State& state) {
  const double noise = state.range(0) / 100.0;
  const bool refine = state.range(1) != 0;
  const Truth truth = MakeTruth(kF, kZ, 48);
  const ema::FrfSet data = MakeFrfSet(truth, Refs(48), 500.0, 0.125, noise, 5);
  ema::curvefit::FitOptions options;
  options.refine = refine ? ema::curvefit::RefineMethod::kMl : ema::curvefit::RefineMethod::kNone;
  options.polymax.threads = options.ml.threads = static_cast<int>(state.range(2));
  ema::curvefit::FitResult fit;
  for (auto _ : state) {
    fit = ema::curvefit::Fit(data, options);
    benchmark::DoNotOptimize(fit.modes.modes.data());
  }
  const auto& t = fit.timing;
  state.counters["polymax_cpu_s"] = t.polymax.normal_equations + t.polymax.solves + t.polymax.eigenvalues;
  state.counters["polymax_wall_s"] = t.polymax.normal_equations_wall + t.polymax.solve_and_eigen_wall;
  state.counters["refine_wall_s"] = t.refine_wall;
  state.counters["refine_cpu_s"] = t.refine;  // all of it with 1 thread (the caller's CPU clock)
  state.counters["lsfd_cpu_s"] = t.lsfd;
  state.counters["ml_iterations"] = fit.refine.iterations;
  double df, dz;
  int found;
  WorstErrors(fit.modes, &df, &dz, &found);
  state.counters["modes_found"] = found;
  state.counters["max_rel_err_f"] = df;
  state.counters["max_rel_err_zeta"] = dz;
}
// Args: noise in %, refine (0 = none: PolyMAX/LSFD + sigma only, 1 = ml), threads (1: the CPU
// counters are the whole cost of each stage).
BENCHMARK(BM_Fit144)->Args({1, 0, 1})->Args({1, 1, 1})->Args({5, 0, 1})->Args({5, 1, 1})->Args({1, 1, 2})->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(1.0);

int WriteGvt(const char* path) {
  const Truth truth = MakeTruth(kF, kZ, 1000);
  const ema::FrfSet data = MakeFrfSet(truth, Refs(1000), 500.0, 0.125, 0.01, 9);
  ema::FrfSet trimmed = data;  // drop the DC line (as an analyser's FRF export starts at df)
  trimmed.frequency_hz = data.frequency_hz.tail(data.LineCount() - 1);
  for (size_t r = 0; r < data.h.size(); ++r) trimmed.h[r] = data.h[r].bottomRows(data.LineCount() - 1);
  ema::formats::WriteFrfSet(path, trimmed);
  std::cout << "wrote " << path << ": " << trimmed.OutputCount() << " responses x " << trimmed.ReferenceCount()
            << " references x " << trimmed.LineCount() << " lines\n";
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc == 3 && std::strcmp(argv[1], "--write-gvt") == 0) return WriteGvt(argv[2]);
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
