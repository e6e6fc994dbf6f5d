// Diagnosis speed. Issue 7 item 6: a 3-body model with 20 springs, 12 test modes and ~15
// candidate effects must be diagnosed in under 10 s. Issue 13: each acceptance case (the
// articles of tests/diagnose/acceptance_test.cpp, full search: members, points, up to three
// effects) in under 5 s. Test modes: the truth model's modes below 1000 Hz (the acceptance
// chain's fit band) with 0.02 % frequency noise and 1 % shape noise (fixed seed), about what
// the simulate → frf → fit chain leaves.
#include <benchmark/benchmark.h>

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <random>

#include "diagnose/article_models.hpp"
#include "ema/diagnose/diagnose.hpp"
#include "ema/formats/model_file.hpp"
#include "ema/model/effects.hpp"
#include "ema/model/solve.hpp"

using ema::model::EffectTarget;

namespace {

using namespace ema;

model::Law FilmChain(double setting) {
  model::AirFilmLaw film;
  for (int i = 0; i <= 80; ++i) {
    const double h = (0.5 + 0.75 * i) * 1e-6;
    film.gap.push_back(h);
    film.load.push_back(300.0 * std::exp(-h / 6e-6));
  }
  model::SeriesLaw chain;
  chain.elements.push_back(model::Law(film));
  chain.setting = setting;
  return model::Law(chain);
}

model::Spring MakeSpring(const std::string& group, const std::string& a, const std::string& b, Eigen::Vector3d at,
                         Eigen::Vector3d dir, model::Law law) {
  static int n = 0;
  model::Spring s;
  s.name = group + std::to_string(++n);
  s.group = group;
  s.a = model::Anchor{a, 0, at, true};
  s.b = model::Anchor{b, 0, at, true};
  s.direction = dir.normalized();
  s.law = std::move(law);
  return s;
}

model::Model ThreeBodies() {
  model::Model m;
  m.name = "bench: carriage / saddle / base";
  m.bodies = {{"carriage", 2.9, {0.012, 0.015, 0.010}, Eigen::Vector3d::Zero(), Eigen::Vector3d(0, 0, 0), 0},
              {"saddle", 6.0, {0.03, 0.04, 0.05}, Eigen::Vector3d::Zero(), Eigen::Vector3d(0, 0, -0.06), 0},
              {"base", 15.0, {0.10, 0.14, 0.20}, Eigen::Vector3d::Zero(), Eigen::Vector3d(0, 0, -0.14), 0}};
  // 8 bearing pads (4 vertical, 4 lateral), 4 joints, 8 mounts = 20 springs.
  for (double x : {-0.06, 0.06})
    for (double y : {-0.03, 0.03}) {
      m.springs.push_back(MakeSpring("bearings", "carriage", "saddle", {x, y, -0.03}, {0, 0, 1}, FilmChain(5e-6)));
      m.springs.push_back(MakeSpring("bearings", "carriage", "saddle", {x, 1.5 * y, 0.0}, {0, y > 0 ? -1.0 : 1.0, 0.2},
                                     FilmChain(5e-6)));
    }
  for (double x : {-0.08, 0.08})
    for (double y : {-0.05, 0.05})
      m.springs.push_back(MakeSpring("joints", "saddle", "base", {x, y, -0.1}, {0.3 * x / 0.08, 0.2, 1.0},
                                     model::Law(model::LinearLaw{4e7})));
  for (double x : {-0.12, 0.12})
    for (double y : {-0.1, 0.1}) {
      m.springs.push_back(MakeSpring("mounts", "base", model::kGround, {x, y, -0.2}, {0, 0, 1}, model::Law(model::LinearLaw{1e7})));
      m.springs.push_back(MakeSpring("mounts", "base", model::kGround, {x, y, -0.2}, {1, x > 0 ? 1.0 : -0.5, 0},
                                     model::Law(model::LinearLaw{4e6})));
    }
  int id = 100;
  const char* bodies[] = {"carriage", "saddle", "base"};
  const double z[] = {0.03, -0.04, -0.12};
  for (int b = 0; b < 3; ++b)
    for (double x : {-0.07, 0.07})
      for (double y : {-0.04, 0.04}) m.points.push_back({++id, model::Anchor{bodies[b], 0, {x, y, z[b]}, true}, 0});
  m.damping.ratio = 0.01;
  return m;
}

// True when rank 1 holds exactly the truth's effects (kind and target, in order); none for none.
bool RanksTruthFirst(const diagnose::Diagnosis& d, const std::vector<model::Effect>& truth) {
  const std::vector<model::Effect>& first = d.candidates.front().effects;
  if (first.size() != truth.size()) return false;
  for (std::size_t i = 0; i < truth.size(); ++i)
    if (first[i].kind != truth[i].kind || first[i].target != truth[i].target) return false;
  return true;
}

void BM_Diagnose3Bodies20Springs12Modes(benchmark::State& state) {
  const model::Model nominal = ThreeBodies();
  model::Effect truth{
      model::EffectKind::kSeriesCompliance, EffectTarget::Named("bearings"), {}, model::Law(model::LinearLaw{8e6}), 0};
  ModeSet test = model::Solve(model::ApplyEffect(nominal, truth)).modes;
  test.modes.resize(12);
  std::mt19937 rng(3);
  std::normal_distribution<double> g;
  for (Mode& mode : test.modes) {
    mode.frequency_hz *= 1.0 + 1e-3 * g(rng);
    const double rms = mode.shape.norm() / std::sqrt(static_cast<double>(mode.shape.size()));
    for (Eigen::Index i = 0; i < mode.shape.size(); ++i)
      mode.shape(i) += 0.01 * rms * std::complex<double>(g(rng), g(rng));
  }
  diagnose::Diagnosis d;
  for (auto _ : state) {
    d = diagnose::Diagnose(nominal, {{"", test}});
    benchmark::DoNotOptimize(d);
  }
  int singles = 0;
  for (const auto& c : d.candidates) singles += c.effects.size() == 1;
  state.counters["candidates"] = singles;
  state.counters["model_solves"] = d.model_solves;
  state.counters["rank1_is_truth"] = RanksTruthFirst(d, {truth});
  state.SetLabel(d.candidates.front().kind + " of " + d.candidates.front().target);
}
BENCHMARK(BM_Diagnose3Bodies20Springs12Modes)->Unit(benchmark::kMillisecond)->Iterations(3);

namespace fs = std::filesystem;

ModeSet NoisyModes(const model::Model& truth, unsigned seed) {
  ModeSet test = model::Solve(truth).modes;
  std::vector<Mode> kept;
  for (const Mode& m : test.modes)
    if (m.frequency_hz >= 40.0 && m.frequency_hz <= 1000.0) kept.push_back(m);
  test.modes = kept;
  std::mt19937 rng(seed);
  std::normal_distribution<double> g;
  for (Mode& mode : test.modes) {
    mode.frequency_hz *= 1.0 + 2e-4 * g(rng);
    const double rms = mode.shape.norm() / std::sqrt(static_cast<double>(mode.shape.size()));
    for (Eigen::Index i = 0; i < mode.shape.size(); ++i)
      mode.shape(i) += 0.01 * rms * std::complex<double>(g(rng), g(rng));
  }
  return test;
}

// One acceptance case: the model file written to a scratch folder, the truth = model + effects.
void RunCase(benchmark::State& state, const fs::path& model_path, const std::vector<model::Effect>& truth_effects) {
  const model::Model nominal = formats::ReadModelFile(model_path);
  model::Model truth = nominal;
  for (const auto& e : truth_effects) truth = model::ApplyEffect(truth, e);
  const ModeSet test = NoisyModes(truth, 7);
  diagnose::Diagnosis d;
  for (auto _ : state) {
    d = diagnose::Diagnose(nominal, {{"", test}});
    benchmark::DoNotOptimize(d);
  }
  state.counters["test_modes"] = static_cast<double>(test.modes.size());
  state.counters["candidates_screened"] = d.candidates_screened;
  state.counters["model_solves"] = d.model_solves;
  state.counters["rank1_is_truth"] = RanksTruthFirst(d, truth_effects);
  state.SetLabel(d.candidates.front().kind + " of " + d.candidates.front().target);
}

fs::path Scratch() {
  const fs::path dir = fs::temp_directory_path() / ("ema-bench-diagnose-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  return dir;
}

void BM_AcceptanceTwoEffects(benchmark::State& state) {
  const fs::path p = Scratch() / "stack.toml";
  test_chain::Write(p, test_chain::StackToml());
  RunCase(state, p,
          {{model::EffectKind::kSeriesCompliance,
            EffectTarget::Named("joints"),
            {},
            model::Law(model::LinearLaw{1.2e7}),
            0},
           {model::EffectKind::kStiffnessScale, EffectTarget::Named("mounts"), {{"factor", 0.6}}, std::nullopt, 0}});
}
BENCHMARK(BM_AcceptanceTwoEffects)->Unit(benchmark::kMillisecond)->Iterations(1);

void BM_AcceptanceOneMemberOfFour(benchmark::State& state) {
  const fs::path p = Scratch() / "stack.toml";
  test_chain::Write(p, test_chain::StackToml());
  RunCase(state, p,
          {{model::EffectKind::kStiffnessScale,
            EffectTarget::MemberOf("joints", "J3"),
            {{"factor", 0.2}},
            std::nullopt,
            0}});
}
BENCHMARK(BM_AcceptanceOneMemberOfFour)->Unit(benchmark::kMillisecond)->Iterations(1);

void BM_AcceptanceFeSupport(benchmark::State& state) {
  test_chain::WriteBeam(Scratch() / "beam");
  RunCase(state, Scratch() / "beam" / "beam.toml",
          {{model::EffectKind::kStiffnessScale,
            EffectTarget::MemberOf("supports", "S2"),
            {{"factor", 0.25}},
            std::nullopt,
            0}});
}
BENCHMARK(BM_AcceptanceFeSupport)->Unit(benchmark::kMillisecond)->Iterations(1);

void BM_AcceptanceAirGap(benchmark::State& state) {
  test_chain::Write(Scratch() / "films" / "lateral.csv", test_chain::FilmArrays(false, true));
  test_chain::Write(Scratch() / "films" / "films.toml", test_chain::ModelToml("bearings", "lateral.csv"));
  RunCase(
      state, Scratch() / "films" / "films.toml",
      {{model::EffectKind::kOperatingPoint, EffectTarget::Named("bearings"), {{"value", 7.5e-6}}, std::nullopt, 0}});
}
BENCHMARK(BM_AcceptanceAirGap)->Unit(benchmark::kMillisecond)->Iterations(1);

void BM_AcceptanceNone(benchmark::State& state) {
  const fs::path p = Scratch() / "stack.toml";
  test_chain::Write(p, test_chain::StackToml());
  RunCase(state, p, {});
}
BENCHMARK(BM_AcceptanceNone)->Unit(benchmark::kMillisecond)->Iterations(1);

}  // namespace

BENCHMARK_MAIN();
