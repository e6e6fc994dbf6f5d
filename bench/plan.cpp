// Test planning (issue 40): "a plan for a 1000-DOF FE model with 200 candidate points and 10
// look-alike readings in < 10 s". The article is the two-girder footbridge frame of
// tests/model/fe_frame.hpp with 100 segments per girder (1 212 DOFs, every inner node a test
// point: 198 points, 594 candidate DOFs); the readings are a 40 kg mass at ten points of the first
// girder (mirror pairs about mid-span, the look-alikes a diagnosis leaves); the plan is 2 roving
// sets of 10 triaxial sensors and 2 references over the default band (6 modes).
#include <benchmark/benchmark.h>
#include <sys/resource.h>

#include "ema/formats/model_file.hpp"
#include "ema/planning/plan.hpp"
#include "model/fe_frame.hpp"

namespace {

using namespace ema;
namespace fs = std::filesystem;

void BM_Plan1200Dofs198PointsTenReadings(benchmark::State& state) {
  testing::FrameSpec spec;
  spec.segments = 100;
  spec.zones = 10;
  spec.points_per_girder = 99;  // every inner node
  const fs::path dir = fs::temp_directory_path() / "ema-bench-plan";
  const testing::FrameFiles files = testing::WriteFrame(dir, spec);
  const model::Model m = formats::ReadModelFile(files.model);
  std::vector<planning::Reading> readings;
  for (int i : {10, 90, 20, 80, 30, 70, 40, 60, 45, 55}) {
    const model::EffectTarget target = model::EffectTarget::Points({1000 + i});
    readings.push_back({"added_mass on " + model::TargetText(target),
                        {{model::EffectKind::kAddedMass, target, {{"mass", 40.0}}, std::nullopt, 0}},
                        ""});
  }
  planning::PlanOptions o;
  o.sensors_per_set = 10, o.sets = 2, o.triaxial = true, o.references = 2;
  planning::TestPlan plan;
  for (auto _ : state) plan = planning::PlanTest(m, o, readings);
  double smallest_before = 1e300, smallest_after = 1e300;
  for (const planning::Separation& s : plan.separations)
    smallest_before = std::min(smallest_before, s.sigma_before), smallest_after = std::min(smallest_after, s.sigma_after);
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  state.counters["dofs"] = files.dofs;
  state.counters["candidate_points"] = static_cast<double>(plan.candidates.size()) / 3.0;
  state.counters["readings"] = static_cast<double>(readings.size());
  state.counters["pairs"] = static_cast<double>(plan.separations.size());
  state.counters["min_sep_before"] = smallest_before;
  state.counters["min_sep_after"] = smallest_after;
  state.counters["automac_max"] = plan.automac_max_offdiagonal;
  state.counters["peak_rss_MB"] = usage.ru_maxrss / 1024.0;
  fs::remove_all(dir);
}
BENCHMARK(BM_Plan1200Dofs198PointsTenReadings)->Unit(benchmark::kMillisecond)->Iterations(1);

}  // namespace

BENCHMARK_MAIN();
