// Diagnosis of FE models built from parts (issue 27 item 3): "a 1000-DOF, 20-part model
// diagnoses with pairs in < 10 s and a 50 000-DOF, 50-part model in < 2 min on 2 cores". The
// articles are the two-girder footbridge frames of tests/model/fe_frame.hpp (3D beams, lumped
// mass with massless rotations, parts: girder zones, cross beams, bearings, a deck part); the
// truth has one girder zone at 40 % of its stiffness; the test is its first six vertical modes
// at the 58 +Z DOFs of the test points, frequencies with 0.1 % noise and σ (fixed seed).
// Peak memory: reported by the program's own getrusage after each case (docs/performance.md).
#include <benchmark/benchmark.h>
#include <sys/resource.h>

#include <cmath>
#include <limits>
#include <random>

#include "ema/diagnose/diagnose.hpp"
#include "ema/formats/model_file.hpp"
#include "ema/model/effects.hpp"
#include "ema/model/reduced.hpp"
#include "ema/model/solve.hpp"
#include "model/fe_frame.hpp"

using ema::model::EffectTarget;

namespace {

using namespace ema;
namespace fs = std::filesystem;

ModeSet VerticalModes(const model::Model& truth, int count, double noise, unsigned seed) {
  model::SolveOptions so;
  so.max_modes = 3 * count;
  const model::Solution s = model::Solve(truth, so);
  ModeSet out;
  std::vector<Eigen::Index> rows;
  for (size_t d = 0; d < s.modes.dofs.size(); ++d)
    if (s.modes.dofs[d].direction == 3) rows.push_back(static_cast<Eigen::Index>(d)), out.dofs.push_back(s.modes.dofs[d]);
  std::mt19937 rng(seed);
  std::normal_distribution<double> gauss(0.0, 1.0);
  for (const Mode& m : s.modes.modes) {
    if (static_cast<int>(out.modes.size()) == count) break;
    double z = 0.0;
    for (Eigen::Index r : rows) z += std::norm(m.shape(r));
    if (z < 0.5 * m.shape.squaredNorm()) continue;
    Mode t = m;
    t.shape.resize(static_cast<Eigen::Index>(rows.size()));
    for (size_t k = 0; k < rows.size(); ++k) t.shape(static_cast<Eigen::Index>(k)) = m.shape(rows[k]);
    t.frequency_hz *= 1.0 + noise * gauss(rng);
    t.frequency_std_hz = noise * m.frequency_hz;
    out.modes.push_back(t);
  }
  return out;
}

// The frame of `segments` elements per girder and `zones` girder zones, written to a scratch folder
// (`tag` keeps the benchmarks' folders apart; the caller removes it) and read back.
struct WrittenFrame {
  fs::path dir;
  testing::FrameFiles files;
  model::Model nominal;
};
WrittenFrame WriteAndReadFrame(int segments, int zones, const std::string& tag) {
  testing::FrameSpec spec;
  spec.segments = segments;
  spec.zones = zones;
  WrittenFrame out;
  out.dir = fs::temp_directory_path() / ("ema-bench-frame-" + tag + std::to_string(segments));
  out.files = testing::WriteFrame(out.dir, spec);
  out.nominal = formats::ReadModelFile(out.files.model);
  return out;
}

// The truth of the frame benchmarks: girder zone G3 at 0.4 of its stiffness.
model::Effect SoftenedG3() {
  return {model::EffectKind::kStiffnessScale, EffectTarget::MemberOf("girders", "G3"), {{"factor", 0.4}}, std::nullopt, 0};
}

void RunFrame(benchmark::State& state, int segments, int zones, bool model_error = true, int polish_swaps = 3,
              double exact_margin = diagnose::DiagnoseOptions{}.exact_margin) {
  const WrittenFrame frame = WriteAndReadFrame(segments, zones, "");
  const fs::path& dir = frame.dir;
  const testing::FrameFiles& files = frame.files;
  const model::Model& nominal = frame.nominal;
  const model::Model truth = model::ApplyEffect(nominal, SoftenedG3());
  const ModeSet test = VerticalModes(truth, 6, 1e-3, 7);
  diagnose::Diagnosis d;
  diagnose::DiagnoseOptions options;
  options.model_error = model_error;
  options.polish_swaps = polish_swaps;
  options.exact_margin = exact_margin;
  for (auto _ : state) d = diagnose::Diagnose(nominal, {{"", test}}, options);
  const diagnose::Candidate& first = d.candidates.front();
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  state.counters["dofs"] = files.dofs;
  state.counters["parts"] = files.parts;
  state.counters["full_solves"] = d.model_solves;
  state.counters["peak_rss_MB"] = usage.ru_maxrss / 1024.0;
  state.counters["rank1_right"] =
      first.effects.size() == 1 && first.effects[0].target == ema::model::EffectTarget::MemberOf("girders", "G3");
  state.counters["factor"] = first.parameters.empty() ? 0.0 : first.parameters[0].value;
  fs::remove_all(dir);
}

// 972 DOFs, 17 parts (the test articles' size: girders G1..G8, cross X1..X4, bearings B1..B4, deck).
void BM_DiagnoseFrame1000Dofs17Parts(benchmark::State& state) { RunFrame(state, 80, 8); }
BENCHMARK(BM_DiagnoseFrame1000Dofs17Parts)->Unit(benchmark::kMillisecond)->Iterations(1);

// 1 212 DOFs, 20 parts (zones 10: G1..G10, X1..X5, B1..B4, deck).
void BM_DiagnoseFrame1200Dofs20Parts(benchmark::State& state) { RunFrame(state, 100, 10); }
BENCHMARK(BM_DiagnoseFrame1200Dofs20Parts)->Unit(benchmark::kMillisecond)->Iterations(1);

// The real-sized case of issue 37 item 6: the 17-part frame (972 DOFs) with each part's
// uncertainty stated as engineers state it (girders and cross beams 10 %, deck 30 %, bearings
// 100 %), five vertical test modes at the 58 +Z test DOFs, and a truth the model cannot express:
// one girder zone at 60 %, every other part off by a 3 % scatter and every node's mass by 3 %
// (model-form error), frequencies with 0.2 % noise and σ. `geometry`: false drops the node
// positions (a model given without its nodes file).
void RunFootbridge(benchmark::State& state, bool geometry) {
  testing::FrameSpec spec;
  spec.segments = 80;
  spec.zones = 8;
  spec.part_uncertainty = 0.1;
  spec.deck_uncertainty = 0.3;
  spec.bearing_uncertainty = 1.0;
  const fs::path dir = fs::temp_directory_path() / "ema-bench-footbridge";
  const testing::FrameFiles files = testing::WriteFrame(dir, spec);
  model::Model nominal = formats::ReadModelFile(files.model);
  if (!geometry) nominal.fe.node_positions.clear();
  model::Model truth = model::ApplyEffect(nominal, {model::EffectKind::kStiffnessScale,
                                                    EffectTarget::MemberOf("girders", "G3"),
                                                    {{"factor", 0.6}},
                                                    std::nullopt,
                                                    0});
  std::mt19937 rng(37);
  std::normal_distribution<double> gauss(0.0, 1.0);
  for (model::FePart& part : truth.fe.parts) part.stiffness_factor *= std::exp(0.03 * gauss(rng));
  Eigen::SparseMatrix<double> m = truth.fe.mass;
  for (int k = 0; k < m.outerSize(); ++k)
    for (Eigen::SparseMatrix<double>::InnerIterator it(m, k); it; ++it) it.valueRef() *= 1.0 + 0.03 * gauss(rng);
  m = 0.5 * (m + Eigen::SparseMatrix<double>(m.transpose()));
  truth.fe.mass = m;
  const ModeSet test = VerticalModes(truth, 5, 2e-3, 7);
  diagnose::Diagnosis d;
  for (auto _ : state) d = diagnose::Diagnose(nominal, {{"", test}});
  const diagnose::Candidate& first = d.candidates.front();
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  state.counters["dofs"] = files.dofs;
  state.counters["parts"] = files.parts;
  state.counters["test_dofs"] = static_cast<double>(test.dofs.size());
  state.counters["full_solves"] = d.model_solves;
  state.counters["peak_rss_MB"] = usage.ru_maxrss / 1024.0;
  state.counters["rank1_right"] =
      first.effects.size() == 1 && first.effects[0].target == ema::model::EffectTarget::MemberOf("girders", "G3");
  state.counters["rank1_probability"] = first.probability;
  fs::remove_all(dir);
}
void BM_DiagnoseFootbridge1000Dofs17PartsModelError(benchmark::State& state) { RunFootbridge(state, true); }
BENCHMARK(BM_DiagnoseFootbridge1000Dofs17PartsModelError)->Unit(benchmark::kMillisecond)->Iterations(1);
void BM_DiagnoseFootbridge1000Dofs17PartsNoNodes(benchmark::State& state) { RunFootbridge(state, false); }
BENCHMARK(BM_DiagnoseFootbridge1000Dofs17PartsNoNodes)->Unit(benchmark::kMillisecond)->Iterations(1);

// 12 012 DOFs, 50 parts (a step between the two).
void BM_DiagnoseFrame12000Dofs50Parts(benchmark::State& state) { RunFrame(state, 1000, 30); }
BENCHMARK(BM_DiagnoseFrame12000Dofs50Parts)->Unit(benchmark::kMillisecond)->Iterations(1);

// The same with the model's form taken as exact (--exact-form): what the model error costs.
void BM_DiagnoseFrame12000Dofs50PartsExactForm(benchmark::State& state) { RunFrame(state, 1000, 30, false); }
BENCHMARK(BM_DiagnoseFrame12000Dofs50PartsExactForm)->Unit(benchmark::kMillisecond)->Iterations(1);
// ... and without the polished swaps of look-alikes (DiagnoseOptions::polish_swaps = 0).
void BM_DiagnoseFrame12000Dofs50PartsExactFormNoSwaps(benchmark::State& state) { RunFrame(state, 1000, 30, false, 0); }
BENCHMARK(BM_DiagnoseFrame12000Dofs50PartsExactFormNoSwaps)->Unit(benchmark::kMillisecond)->Iterations(1);

// ... with every one of the best 8 sets and their subsets checked by full solves, whatever their
// score (DiagnoseOptions::exact_margin infinite: the diagnosis before 2026-11-28).
void BM_DiagnoseFrame12000Dofs50PartsEveryCheck(benchmark::State& state) {
  RunFrame(state, 1000, 30, true, 3, std::numeric_limits<double>::infinity());
}
BENCHMARK(BM_DiagnoseFrame12000Dofs50PartsEveryCheck)->Unit(benchmark::kMillisecond)->Iterations(1);

// 50 004 DOFs, 50 parts (zones 30: G1..G30, X1..X15, B1..B4, deck).
void BM_DiagnoseFrame50000Dofs50Parts(benchmark::State& state) { RunFrame(state, 4166, 30); }
BENCHMARK(BM_DiagnoseFrame50000Dofs50Parts)->Unit(benchmark::kMillisecond)->Iterations(1);

// One full solve of the frame (its lowest modes by shift-invert, as the diagnosis's checks and
// the centres of its reduced models make them): where the large cases' time goes (#39).
void RunFrameSolve(benchmark::State& state, int segments) {
  const WrittenFrame frame = WriteAndReadFrame(segments, 30, "solve-");
  model::SolveOptions so;
  so.max_modes = 30;
  model::Solution s;
  for (auto _ : state) s = model::Solve(frame.nominal, so);
  state.counters["dofs"] = frame.files.dofs;
  state.counters["modes"] = static_cast<double>(s.modes.modes.size());
  state.counters["f1_hz"] = s.modes.modes.empty() ? 0.0 : s.modes.modes[0].frequency_hz;
  state.counters["f30_hz"] = s.modes.modes.empty() ? 0.0 : s.modes.modes.back().frequency_hz;
  fs::remove_all(frame.dir);
}
void BM_FullSolveFrame12000Dofs(benchmark::State& state) { RunFrameSolve(state, 1000); }
BENCHMARK(BM_FullSolveFrame12000Dofs)->Unit(benchmark::kMillisecond)->Iterations(3);
void BM_FullSolveFrame50000Dofs(benchmark::State& state) { RunFrameSolve(state, 4166); }
BENCHMARK(BM_FullSolveFrame50000Dofs)->Unit(benchmark::kMillisecond)->Iterations(3);

// The reduced model of the diagnosis's search (centred at the nominal model, the truth's effect as
// its probe) against a full solve of the truth: how far the search's screening can trust it. On the
// 50 000-DOF frame it was off by half (a "new" 4.58 Hz mode) while the solver's rigid-body limit
// dropped the frame's four lowest modes; within 0.5 % since (#39, docs/diagnose.md).
void RunReducedAtTruth(benchmark::State& state, int segments) {
  const WrittenFrame frame = WriteAndReadFrame(segments, 30, "reduced-");
  const model::Effect zone = SoftenedG3();
  const model::Model truth = model::ApplyEffect(frame.nominal, zone);
  // As the diagnosis makes them for six test modes (diagnose/src/evaluate.cpp).
  model::SolveOptions so;
  so.max_modes = 20;
  so.sparse_threshold = 200;
  model::ReducedModelOptions ro;
  ro.modes = 30;
  ro.enriched_modes = 10;
  model::Solution reduced, full;
  int basis = 0;
  for (auto _ : state) {
    const model::ReducedModelFactory factory(frame.nominal, so, ro);
    const auto reduced_model = factory.Make({{zone}});
    reduced = reduced_model->Solve(truth, so, false);
    basis = reduced_model->BasisSize();
    full = model::Solve(truth, so);
  }
  double worst = 0.0;
  for (size_t i = 0; i < 6 && i < reduced.modes.modes.size() && i < full.modes.modes.size(); ++i)
    worst = std::max(worst, std::abs(reduced.modes.modes[i].frequency_hz / full.modes.modes[i].frequency_hz - 1.0));
  state.counters["dofs"] = frame.files.dofs;
  state.counters["full_f1_hz"] = full.modes.modes.empty() ? 0.0 : full.modes.modes[0].frequency_hz;
  state.counters["reduced_f1_hz"] = reduced.modes.modes.empty() ? 0.0 : reduced.modes.modes[0].frequency_hz;
  state.counters["worst_rel_error_6"] = worst;
  state.counters["basis"] = basis;
  fs::remove_all(frame.dir);
}
void BM_ReducedAtTruthFrame12000Dofs(benchmark::State& state) { RunReducedAtTruth(state, 1000); }
BENCHMARK(BM_ReducedAtTruthFrame12000Dofs)->Unit(benchmark::kMillisecond)->Iterations(1);
void BM_ReducedAtTruthFrame50000Dofs(benchmark::State& state) { RunReducedAtTruth(state, 4166); }
BENCHMARK(BM_ReducedAtTruthFrame50000Dofs)->Unit(benchmark::kMillisecond)->Iterations(1);

}  // namespace

BENCHMARK_MAIN();
