// `ema pick` on the guideway sample (issue 29): one click's work on the server — the refit of the
// picked set (curvefit::Fit with --select: PolyMAX, selection, ML refinement, LSFD) and the page's
// state (MAC, the synthesised FRFs) — for the sample's 144 FRFs in the band 100–450 Hz. Target:
// the page redrawn within a second of a click; the browser's own part (about 0.1 s) is measured by
// tests/app/pick_test.cpp (PickBrowser.GuidewayPickRedrawsWithinASecond prints it). Results:
// docs/performance.md.
#include <benchmark/benchmark.h>

#include <filesystem>
#include <sstream>

#include "pick/pick_session.hpp"
#include "stages.hpp"

namespace {

namespace fs = std::filesystem;

// The guideway sample's stud-5um FRFs (as `ema frf` writes them), computed once.
const ema::FrfSet& GuidewayFrfs() {
  static const ema::FrfSet frfs = [] {
    const fs::path dir = fs::temp_directory_path() / "ema-bench-pick";
    fs::create_directories(dir);
    ema::app::FrfConfig config;
    config.inputs = {(fs::path(EMA_SOURCE_DIR) / "samples/guideway/data/stud-5um.unv").string()};
    config.output = (dir / "frf.unv").string();
    std::ostringstream quiet;
    return ema::app::RunFrfStage(config, quiet).stored;
  }();
  return frfs;
}

ema::app::PickSession& Session() {
  static ema::app::PickSession session = [] {
    ema::app::FitConfig config;
    config.input = "stud-5um/frf.unv";
    config.options.data.band_lo_hz = 100.0;
    config.options.data.band_hi_hz = 450.0;
    return ema::app::PickSession(config, GuidewayFrfs());
  }();
  return session;
}

// A click that removes the 381 Hz mode (four picked), then one that picks it again (five).
void BM_PickGuidewayClick(benchmark::State& state) {
  ema::app::PickSession& session = Session();
  const nlohmann::json automatic = session.Select({{"selection", "auto"}});  // benchmark reruns this function
  nlohmann::json four = nlohmann::json::array(), five;
  for (const auto& m : automatic["modes"]) four.push_back(m["requested_hz"]);
  five = four;
  four.erase(four.end() - 1);
  bool all = false;
  for (auto _ : state) {
    const nlohmann::json answer = session.Select({{"frequencies_hz", all ? five : four}});
    benchmark::DoNotOptimize(answer.dump().size());  // the page's answer, serialised as sent
    all = !all;
  }
  state.counters["modes_auto"] = static_cast<double>(automatic["modes"].size());
}
BENCHMARK(BM_PickGuidewayClick)->Unit(benchmark::kMillisecond)->UseRealTime();

// The page's first data (diagram, indicators, measured FRFs, state): once per page load.
void BM_PickGuidewayPageData(benchmark::State& state) {
  ema::app::PickSession& session = Session();
  for (auto _ : state) benchmark::DoNotOptimize(session.DataJson().dump().size());
}
BENCHMARK(BM_PickGuidewayPageData)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
