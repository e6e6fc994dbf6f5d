// Hammer test to H1 + coherence: 48 response channels × 10 impacts × 65 536 samples (issue 3 item
// 7), against bare FFTW doing the same 490 real transforms in the same run. Target: ≤ 2×.
// Results: docs/perf/frf.md.
#include <benchmark/benchmark.h>
#include <fftw3.h>

#include <cmath>
#include <cstring>
#include <filesystem>

#include "ema/acquisition/hammer_measurement.hpp"
#include "ema/acquisition/simulator.hpp"
#include "ema/formats/io.hpp"
#include "ema/frf/hammer_frf.hpp"

namespace {

constexpr int kChannels = 48;
constexpr int kImpacts = 10;
constexpr int kSamples = 65536;

// A 48-point beam-like truth (6 modes, sine shapes) and one reference, simulated once.
const std::vector<ema::TimeRecord>& Records() {
  static const std::vector<ema::TimeRecord> records = [] {
    ema::acquisition::ModalTruth truth;
    for (int p = 0; p <= kChannels; ++p) truth.dofs.push_back({p + 1, 3});
    for (int r = 0; r < 6; ++r) {
      truth.poles.push_back(ema::FrequencyAndDampingToPole(40.0 * (r + 1) * (r + 1), 0.01));
      Eigen::VectorXcd shape(kChannels + 1);
      for (int p = 0; p <= kChannels; ++p) shape[p] = std::sin(3.14159265 * (r + 1) * (p + 0.5) / (kChannels + 1));
      truth.shapes.push_back(shape);
    }
    ema::acquisition::HammerTestPlan plan;
    plan.sample_rate_hz = 8192.0;
    plan.samples_per_record = kSamples;
    plan.references = {{1, 3}};
    plan.roving_sets.resize(1);
    for (int p = 1; p <= kChannels; ++p) plan.roving_sets[0].push_back({p + 1, 3});
    plan.impacts_per_reference = kImpacts;
    plan.response_noise = 0.01;
    plan.force_noise = 0.01;
    plan.oversampling = 4;
    return ema::acquisition::SimulateHammerTest({truth}, plan);
  }();
  return records;
}

void BM_EstimateFrfsH1Coherence(benchmark::State& state) {
  const ema::acquisition::HammerMeasurement test = ema::acquisition::AssembleHammerMeasurement({{"bench", Records()}});
  for (auto _ : state) {
    ema::frf::FrfResult result = ema::frf::EstimateFrfs(test);
    benchmark::DoNotOptimize(result.frfs.h[0].data());
  }
  state.counters["transforms"] = kImpacts * (kChannels + 1);
}
BENCHMARK(BM_EstimateFrfsH1Coherence)->Unit(benchmark::kMillisecond)->MinTime(3.0);

void BM_BareFftwSameTransforms(benchmark::State& state) {
  const std::vector<ema::TimeRecord>& records = Records();
  double* in = fftw_alloc_real(kSamples);
  fftw_complex* out = fftw_alloc_complex(kSamples / 2 + 1);
  fftw_plan plan = fftw_plan_dft_r2c_1d(kSamples, in, out, FFTW_ESTIMATE);
  for (auto _ : state) {
    for (const ema::TimeRecord& r : records) {
      std::memcpy(in, r.samples.data(), sizeof(double) * kSamples);
      fftw_execute(plan);
      benchmark::DoNotOptimize(out[1][0]);
    }
  }
  fftw_destroy_plan(plan);
  fftw_free(in);
  fftw_free(out);
  state.counters["transforms"] = static_cast<double>(records.size());
}
BENCHMARK(BM_BareFftwSameTransforms)->Unit(benchmark::kMillisecond)->MinTime(3.0);

// From a UFF file (binary 58b, 490 records): read + assemble + H1 + coherence.
void BM_FromUffFile(benchmark::State& state) {
  const std::filesystem::path path = std::filesystem::temp_directory_path() / "ema_bench_frf_time.uff";
  ema::formats::WriteOptions options;
  options.binary = true;
  ema::formats::WriteTimeRecords(path, Records(), options);
  for (auto _ : state) {
    std::vector<ema::acquisition::RecordSet> sets{{path.string(), ema::formats::ReadTimeRecords(path)}};
    ema::frf::FrfResult result = ema::frf::EstimateFrfs(ema::acquisition::AssembleHammerMeasurement(std::move(sets)));
    benchmark::DoNotOptimize(result.frfs.h[0].data());
  }
  std::filesystem::remove(path);
}
BENCHMARK(BM_FromUffFile)->Unit(benchmark::kMillisecond)->Iterations(3);

}  // namespace

BENCHMARK_MAIN();
