// Sparse shift-invert eigen solution of a large FE model: the first 20 modes of a ~1e5-DOF
// model (issue 6 target: < 10 s on the 2-core reference machine). The model is a clamped square
// lattice of point masses with springs on each of the three translations (3 DOF per node), built
// in memory (no file I/O in the timing).
#include <benchmark/benchmark.h>

#include "ema/formats/model_file.hpp"
#include "ema/model/effects.hpp"
#include "ema/model/solve.hpp"

using ema::model::EffectTarget;

namespace {

ema::model::Model Lattice(int side) {
  ema::model::Model m;
  m.name = "lattice";
  const double mass = 0.01, k[3] = {1e6, 1.3e6, 0.4e6};
  auto index = [&](int i, int j) { return (i - 1) * side + j; };  // column i = 0 is clamped
  const int nodes = (side - 1) * side, n = 3 * nodes;
  std::vector<Eigen::Triplet<double>> kt, mt;
  auto couple = [&](int a, int b, double kk) {  // a, b: DOF indices, b < 0 = clamped
    kt.emplace_back(a, a, kk);
    if (b >= 0) {
      kt.emplace_back(b, b, kk);
      kt.emplace_back(a, b, -kk);
      kt.emplace_back(b, a, -kk);
    }
  };
  for (int i = 1; i < side; ++i)
    for (int j = 0; j < side; ++j) {
      const int node = index(i, j);
      for (int c = 0; c < 3; ++c) {
        const int dof = 3 * node + c;
        mt.emplace_back(dof, dof, mass);
        couple(dof, i == 1 ? -1 : 3 * index(i - 1, j) + c, k[c]);   // towards the clamp
        if (j + 1 < side) couple(dof, 3 * index(i, j + 1) + c, k[c]);  // across
      }
      m.fe.dofs.push_back({node + 1, 1});
      m.fe.dofs.push_back({node + 1, 2});
      m.fe.dofs.push_back({node + 1, 3});
    }
  m.fe.stiffness.resize(n, n);
  m.fe.stiffness.setFromTriplets(kt.begin(), kt.end());
  m.fe.mass.resize(n, n);
  m.fe.mass.setFromTriplets(mt.begin(), mt.end());
  m.damping.ratio = 0.01;
  return m;
}

void BM_SparseFirst20Modes(benchmark::State& state) {
  const ema::model::Model model = Lattice(static_cast<int>(state.range(0)));
  ema::model::SolveOptions options;
  options.max_modes = 20;
  for (auto _ : state) {
    const ema::model::Solution sol = ema::model::Solve(model, options);
    benchmark::DoNotOptimize(sol.modes.modes.data());
    if (sol.modes.modes.size() != 20 || !sol.sparse) state.SkipWithError("expected 20 modes from the sparse path");
  }
  state.counters["dof"] = static_cast<double>(model.fe.dofs.size());
}

/// The call the diagnose loop repeats: the thesis carriage (6 DOF, ten air-film + Hertz chains
/// solved for their equilibrium) with one effect applied.
void BM_CarriageSolveWithEffect(benchmark::State& state) {
  const ema::model::Model model =
      ema::formats::ReadModelFile(std::string(EMA_SOURCE_DIR) + "/tests/model/data/carriage.toml");
  const ema::model::Effect effect{ema::model::EffectKind::kSeriesCompliance,
                                  EffectTarget::Named("bearings"),
                                  {},
                                  ema::model::Law(ema::model::LinearLaw{2e7}),
                                  0};
  ema::model::SolveOptions options;
  options.setup = "stud-5um";
  for (auto _ : state) {
    const ema::model::Solution sol = ema::model::Solve(ema::model::ApplyEffect(model, effect), options);
    benchmark::DoNotOptimize(sol.modes.modes.data());
  }
}
BENCHMARK(BM_CarriageSolveWithEffect)->Unit(benchmark::kMicrosecond);

}  // namespace

// side 183: 182 x 183 nodes x 3 = 99,918 DOF; side 100: ~30,000 DOF.
BENCHMARK(BM_SparseFirst20Modes)->Arg(100)->Arg(183)->Unit(benchmark::kSecond)->Iterations(1);
BENCHMARK_MAIN();
