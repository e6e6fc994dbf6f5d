// Reading a generated 500 MB ASCII UFF 58 file (issue 2 item 8; target >= 400 MB/s on one
// core). The file is written once to /tmp and deleted at exit. Figures: docs/perf/formats.md.
#include <benchmark/benchmark.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <unistd.h>

#include "ema/formats/uff.hpp"

namespace {

namespace fs = std::filesystem;
namespace uff = ema::formats::uff;

/// 500 MB of time records: real single precision, even spacing (case 1: 6 x E13.5 per line),
/// 200 datasets of 234 000 noisy samples each.
class BigFile {
 public:
  BigFile() {
    const char* size_env = std::getenv("EMA_BENCH_UFF_MB");
    const double mb = size_env ? std::atof(size_env) : 500.0;
    path_ = fs::temp_directory_path() / ("ema_bench_uff_" + std::to_string(getpid()) + ".uff");
    std::ofstream out(path_, std::ios::binary);
    std::mt19937 rng(1);
    std::normal_distribution<double> noise(0.0, 1.0);
    const int per_dataset = 234000;
    const double bytes_per_dataset = per_dataset / 6.0 * 80.0 + 1000.0;
    const int datasets = std::max(1, static_cast<int>(mb * 1e6 / bytes_per_dataset));
    for (int k = 0; k < datasets; ++k) {
      uff::Function58 f;
      f.function_type = 1;
      f.load_case = 1 + k / 4;
      f.response_node = 101 + k % 4;
      f.response_direction = 3;
      f.reference_node = 1;
      f.reference_direction = 3;
      f.ordinate_type = 2;
      f.count = per_dataset;
      f.dx = 1.0 / 51200.0;
      f.axes[0] = {17, 0, 0, 0, "Time", "s"};
      f.axes[1] = {12, 1, 0, 0, "Acceleration", "m/s^2"};
      f.y.resize(per_dataset);
      for (auto& v : f.y) v = noise(rng) * 3.7e-2;
      uff::WriteDataset(out, uff::DatasetBody(std::move(f)));
    }
    out.close();
    bytes_ = fs::file_size(path_);
  }
  ~BigFile() {
    std::error_code ec;
    fs::remove(path_, ec);
  }
  const fs::path& path() const { return path_; }
  std::uint64_t bytes() const { return bytes_; }

 private:
  fs::path path_;
  std::uint64_t bytes_ = 0;
};

BigFile& File() {
  static BigFile file;
  return file;
}

void BM_ReadAscii58(benchmark::State& state) {
  const BigFile& file = File();
  std::uint64_t values = 0;
  uff::ReadOptions options;
  if (state.range(0) == 0) options.parallel_min_bytes = 0;  // Arg 0: one thread; 1: default (two threads)
  for (auto _ : state) {
    uff::Reader reader(file.path(), options);
    uff::Dataset d;
    while (reader.Next(&d)) values += std::get<uff::Function58>(d.body).y.size();
    benchmark::DoNotOptimize(values);
  }
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations() * file.bytes()));
  state.counters["file_MB"] = static_cast<double>(file.bytes()) / 1e6;
}
BENCHMARK(BM_ReadAscii58)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->Iterations(3)->UseRealTime();

void BM_HeaderScanAscii58(benchmark::State& state) {
  const BigFile& file = File();
  uff::ReadOptions options;
  options.headers_only = true;
  for (auto _ : state) {
    uff::Reader reader(file.path(), options);
    uff::Dataset d;
    int n = 0;
    while (reader.Next(&d)) ++n;
    benchmark::DoNotOptimize(n);
  }
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations() * file.bytes()));
}
BENCHMARK(BM_HeaderScanAscii58)->Unit(benchmark::kMillisecond)->Iterations(3)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
