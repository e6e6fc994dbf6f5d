// PolyMAX on the issue-4 benchmark case: 144 FRFs (16 points × 3 directions × 3 references) ×
// 4000 lines, every order 1..80 (240 poles at the top), then selection and LSFD.
// Run: build/bench/bench_polymax (prints the split of the last run as counters).
#include <benchmark/benchmark.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <random>

#include "ema/curvefit/fit.hpp"

namespace {

using ema::FrfSet;

/// 20 modes in 0..2000 Hz (zeta 0.5-2 %), smooth shapes at 48 DOFs, references at 3 of them,
/// accelerance with 1 % complex noise.
FrfSet BenchmarkData() {
  const int n_lines = 4000, n_dof = 48, n_modes = 20;
  const double df = 0.5;
  FrfSet set;
  set.frequency_hz = Eigen::VectorXd::LinSpaced(n_lines, df, n_lines * df);
  for (int p = 0; p < 16; ++p)
    for (int d = 1; d <= 3; ++d) set.outputs.push_back({p + 1, d});
  const int refs[3] = {4, 22, 40};
  for (int r : refs) set.references.push_back(set.outputs[r]);
  std::vector<std::complex<double>> poles;
  Eigen::MatrixXd phi(n_dof, n_modes);
  for (int r = 0; r < n_modes; ++r) {
    const double f = 60.0 + 90.0 * r + 7.0 * std::sin(r), zeta = 0.005 + 0.015 * (r % 4) / 3.0;
    poles.push_back(ema::FrequencyAndDampingToPole(f, zeta));
    for (int d = 0; d < n_dof; ++d) phi(d, r) = std::sin((r + 1) * 0.37 * (d + 1) + 0.2 * r) * 0.3;
  }
  std::mt19937 rng(3);
  std::normal_distribution<double> g(0.0, 1.0);
  for (int r : refs) {
    Eigen::MatrixXcd h(n_lines, n_dof);
    for (int k = 0; k < n_lines; ++k) {
      const std::complex<double> jw(0.0, ema::kTwoPi * set.frequency_hz[k]);
      for (int d = 0; d < n_dof; ++d) {
        std::complex<double> v = 0.0;
        for (int m = 0; m < n_modes; ++m) {
          const std::complex<double> res = phi(d, m) * phi(r, m) / std::complex<double>(0.0, 2.0 * poles[m].imag());
          v += res / (jw - poles[m]) + std::conj(res) / (jw - std::conj(poles[m]));
        }
        h(k, d) = v * jw * jw;
      }
    }
    for (int d = 0; d < n_dof; ++d) {
      const double rms = std::sqrt(h.col(d).squaredNorm() / n_lines);
      for (int k = 0; k < n_lines; ++k) h(k, d) += 0.01 * rms * std::complex<double>(g(rng), g(rng)) / std::sqrt(2.0);
    }
    set.h.push_back(h);
  }
  return set;
}

void BM_PolymaxFit(benchmark::State& state) {
  static const FrfSet data = BenchmarkData();
  ema::curvefit::FitOptions options;
  options.polymax.order_max = 80;
  options.polymax.threads = options.ml.threads = static_cast<int>(state.range(0));
  // Arg 2 (refine): 0 = the issue-4 pipeline (PolyMAX, selection, LSFD; sigma only), 1 = with the
  // ML refinement of issue 18.
  options.refine = state.range(1) ? ema::curvefit::RefineMethod::kMl : ema::curvefit::RefineMethod::kNone;
  ema::curvefit::FitResult fit;
  for (auto _ : state) {
    fit = ema::curvefit::Fit(data, options);
    benchmark::DoNotOptimize(fit.modes.modes.data());
  }
  const auto& t = fit.timing;
  state.counters["normal_eq_cpu_s"] = t.polymax.normal_equations;
  state.counters["solves_cpu_s"] = t.polymax.solves;
  state.counters["eig_cpu_s"] = t.polymax.eigenvalues;
  state.counters["solve_eig_wall_s"] = t.polymax.solve_and_eigen_wall;
  state.counters["selection_cpu_s"] = t.stabilisation_and_selection;
  state.counters["lsfd_cpu_s"] = t.lsfd;
  state.counters["refine_cpu_s"] = t.refine;  // caller's thread only (all of it with 1 thread)
  state.counters["refine_wall_s"] = t.refine_wall;
  state.counters["modes"] = static_cast<double>(fit.modes.modes.size());
}
BENCHMARK(BM_PolymaxFit)->Args({1, 0})->Args({2, 0})->Args({1, 1})->Args({2, 1})->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(2.0);
BENCHMARK(BM_PolymaxFit)->Args({1, 0})->Args({1, 1})->Unit(benchmark::kMillisecond)->MinTime(2.0);  // CPU-time view

/// The bare cost of the same eigenproblems: real nonsymmetric eigenvalues of random dense
/// matrices of sizes 3p, p = 1..80 (what any companion-matrix method must pay), one thread.
void BM_BareEigenvalues(benchmark::State& state) {
  std::mt19937 rng(1);
  std::normal_distribution<double> g(0.0, 1.0);
  std::vector<Eigen::MatrixXd> mats;
  for (int p = 1; p <= 80; ++p) {
    Eigen::MatrixXd a(3 * p, 3 * p);
    for (int i = 0; i < a.size(); ++i) a.data()[i] = g(rng);
    mats.push_back(a);
  }
  for (auto _ : state)
    for (const auto& a : mats) {
      Eigen::EigenSolver<Eigen::MatrixXd> es(a, false);
      benchmark::DoNotOptimize(es.eigenvalues().data());
    }
}
BENCHMARK(BM_BareEigenvalues)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(2.0);

}  // namespace

BENCHMARK_MAIN();
