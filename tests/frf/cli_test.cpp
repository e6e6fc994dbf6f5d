// End-to-end tests of `ema frf` (cli.md): simulated hammer sets written as UFF 58 time records,
// run through the executable, FRFs read back and compared with the analytic truth.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "acquisition/three_dof.hpp"
#include "ema/acquisition/simulator.hpp"
#include "ema/formats/io.hpp"

namespace ema {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

struct RunResult {
  int code;
  std::string out, err;
};

RunResult RunEma(const std::string& arguments, const fs::path& dir) {
  const fs::path out = dir / "stdout.txt", err = dir / "stderr.txt";
  const std::string cmd = std::string("\"") + EMA_EXECUTABLE + "\" " + arguments + " >\"" + out.string() + "\" 2>\"" +
                          err.string() + "\"";
  const int status = std::system(cmd.c_str());
  auto slurp = [](const fs::path& p) {
    std::ifstream in(p);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
  };
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, slurp(out), slurp(err)};
}

class FrfCli : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!fs::exists(EMA_EXECUTABLE)) FAIL() << "ema executable not built: " << EMA_EXECUTABLE;
    dir_ = fs::path(EMA_TEST_TMP_DIR) / ("frf_cli_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    sys_ = testing::MakeThreeDof();
    plan_.references = {{1, 3}};
    plan_.roving_sets = {{{1, 3}, {2, 3}}, {{3, 3}}};
    plan_.samples_per_record = 8192;
    plan_.force_noise = 0.005;
    plan_.response_noise = 0.005;
  }
  void Write(const acquisition::HammerTestPlan& plan, const std::vector<std::string>& names) {
    const auto sets = acquisition::SimulateHammerTestSets({sys_.truth}, plan);
    for (size_t s = 0; s < names.size(); ++s) formats::WriteTimeRecords(dir_ / names[s], sets[s].records);
  }
  std::string P(const std::string& name) const { return "\"" + (dir_ / name).string() + "\""; }

  fs::path dir_;
  testing::ThreeDof sys_;
  acquisition::HammerTestPlan plan_;
};

TEST_F(FrfCli, TwoRovingSetsToFrfsAndSummary) {
  // A double hit in set 2, impact 2. Expected: exit 0; three FRFs from reference 1+Z read back
  // within 2 % of the analytic accelerance at the resonance lines (0.5 % noise, 5 averages; the
  // ASCII UFF round trip keeps ≥ 1e-6 relative); JSON per cli.md with the rejected impact.
  plan_.double_hits.push_back({1, 0, 2, 3e-3, 0.3});
  Write(plan_, {"set1.unv", "set2.unv"});
  const RunResult r = RunEma("frf " + P("set1.unv") + " " + P("set2.unv") + " -o " + P("frf.unv") + " --json " + P("s.json"), dir_);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("3 FRF(s)"));
  const FrfSet set = formats::ReadFrfSet(dir_ / "frf.unv");
  ASSERT_EQ(set.ReferenceCount(), 1);
  ASSERT_EQ(set.OutputCount(), 3);
  EXPECT_EQ(set.references[0], (Dof{1, 3}));
  for (int o = 0; o < 3; ++o) {
    const Eigen::VectorXcd truth = acquisition::AnalyticFrf(sys_.truth, set.outputs[o], set.references[0], set.frequency_hz);
    for (double f : sys_.frequency_hz) {
      const int i = static_cast<int>(std::lround(f / (set.frequency_hz[1] - set.frequency_hz[0]) - set.frequency_hz[0]));
      EXPECT_LT(std::abs(set.h[0](i, o) - truth[i]), 0.02 * std::abs(truth[i])) << DofName(set.outputs[o]) << " " << f;
    }
  }
  std::ifstream in(dir_ / "s.json");
  const nlohmann::json j = nlohmann::json::parse(in);
  ASSERT_EQ(j["frfs"].size(), 3u);
  int with_rejection = 0;
  for (const auto& e : j["frfs"]) {
    EXPECT_EQ(e["reference_node"], 1);
    EXPECT_EQ(e["reference_dir"], "+Z");
    EXPECT_TRUE(e.contains("response_node") && e.contains("response_dir") && e.contains("averages"));
    if (e["response_node"] == 3) {
      EXPECT_EQ(e["averages"], 4);
      ASSERT_EQ(e["rejected"].size(), 1u);
      EXPECT_EQ(e["rejected"][0]["impact"], 2);
      EXPECT_THAT(e["rejected"][0]["reason"].get<std::string>(), HasSubstr("double hit"));
      ++with_rejection;
    } else {
      EXPECT_EQ(e["averages"], 5);
      EXPECT_TRUE(e["rejected"].empty());
    }
  }
  EXPECT_EQ(with_rejection, 1);
}

TEST_F(FrfCli, DifferentReferenceAndAllRejectedExitOneWritingNothing) {
  plan_.roving_sets = {{{2, 3}}};
  plan_.samples_per_record = 2048;
  Write(plan_, {"a.unv"});
  auto other = plan_;
  other.references = {{3, 3}};
  other.roving_sets = {{{1, 3}}};  // other sensors too: not a roving hammer split over files
  Write(other, {"b.unv"});
  RunResult r = RunEma("frf " + P("a.unv") + " " + P("b.unv") + " -o " + P("out.unv") + " --json " + P("s.json"), dir_);
  EXPECT_EQ(r.code, 1);
  EXPECT_THAT(r.err, HasSubstr("b.unv"));
  EXPECT_THAT(r.err, HasSubstr("must share the reference"));
  EXPECT_FALSE(fs::exists(dir_ / "out.unv"));
  EXPECT_FALSE(fs::exists(dir_ / "s.json"));

  auto doubled = plan_;
  for (int k = 1; k <= plan_.impacts_per_reference; ++k) doubled.double_hits.push_back({0, 0, k, 4e-3, 0.4});
  Write(doubled, {"c.unv"});
  r = RunEma("frf " + P("c.unv") + " -o " + P("out.unv"), dir_);
  EXPECT_EQ(r.code, 1);
  EXPECT_THAT(r.err, HasSubstr("c.unv"));
  EXPECT_THAT(r.err, HasSubstr("double hit"));
  EXPECT_FALSE(fs::exists(dir_ / "out.unv"));
}

TEST_F(FrfCli, UsageErrorsExitTwo) {
  EXPECT_EQ(RunEma("frf -o " + P("x.unv"), dir_).code, 2);
  plan_.roving_sets = {{{2, 3}}};
  plan_.samples_per_record = 1024;
  Write(plan_, {"a.unv"});
  EXPECT_EQ(RunEma("frf " + P("a.unv") + " -o " + P("x.unv") + " --estimator H9", dir_).code, 2);
  EXPECT_EQ(RunEma("frf " + P("a.unv") + " -o " + P("x.unv") + " --band 5", dir_).code, 2);
  const RunResult help = RunEma("frf --help", dir_);
  EXPECT_EQ(help.code, 0);
  EXPECT_THAT(help.out, HasSubstr("--estimator"));
  EXPECT_FALSE(fs::exists(dir_ / "x.unv"));
}

// ---- One test per option (issue 17): each asserts the option's effect on the output, so an
// option that is ignored or wired to the wrong setting fails.

TEST_F(FrfCli, EstimatorH2IsH1OverCoherence) {
  // H1 = Gxf/Gff, H2 = Gxx/Gfx, so |H2| = |H1| / γ² at every line and both have the same phase.
  // The ASCII UFF round trip keeps ~6 significant digits: 1e-4 relative covers three such values.
  plan_.roving_sets = {{{2, 3}}};
  plan_.response_noise = 0.05;
  Write(plan_, {"a.unv"});
  ASSERT_EQ(RunEma("frf " + P("a.unv") + " -o " + P("h1.unv"), dir_).code, 0);
  ASSERT_EQ(RunEma("frf " + P("a.unv") + " -o " + P("h2.unv") + " --estimator H2", dir_).code, 0);
  const FrfSet h1 = formats::ReadFrfSet(dir_ / "h1.unv"), h2 = formats::ReadFrfSet(dir_ / "h2.unv");
  ASSERT_EQ(h1.LineCount(), h2.LineCount());
  ASSERT_FALSE(h1.coherence.empty());
  int differing = 0;
  for (int i = 1; i < h1.LineCount(); ++i) {
    const double g = h1.coherence[0](i, 0);
    if (g < 1e-3) continue;
    EXPECT_NEAR(std::abs(h2.h[0](i, 0)), std::abs(h1.h[0](i, 0)) / g, 1e-4 * std::abs(h1.h[0](i, 0)) / g) << "line " << i;
    differing += std::abs(h2.h[0](i, 0)) > 1.001 * std::abs(h1.h[0](i, 0));
  }
  EXPECT_GT(differing, h1.LineCount() / 10) << "5 % response noise must lower the coherence on many lines";
}

TEST_F(FrfCli, BandKeepsOnlyItsLinesWithTheSameValues) {
  plan_.roving_sets = {{{2, 3}}};
  plan_.samples_per_record = 2048;
  Write(plan_, {"a.unv"});
  ASSERT_EQ(RunEma("frf " + P("a.unv") + " -o " + P("all.unv"), dir_).code, 0);
  ASSERT_EQ(RunEma("frf " + P("a.unv") + " -o " + P("band.unv") + " --band 20:80", dir_).code, 0);
  const FrfSet all = formats::ReadFrfSet(dir_ / "all.unv"), band = formats::ReadFrfSet(dir_ / "band.unv");
  const double df = all.frequency_hz[1] - all.frequency_hz[0];  // 2 Hz: 4096 Hz / 2048 samples
  ASSERT_GT(band.LineCount(), 0);
  EXPECT_GE(band.frequency_hz[0], 20.0 - 1e-9);
  EXPECT_LT(band.frequency_hz[0], 20.0 + df);
  EXPECT_LE(band.frequency_hz[band.LineCount() - 1], 80.0 + 1e-9);
  EXPECT_GT(band.frequency_hz[band.LineCount() - 1], 80.0 - df);
  const int first = static_cast<int>(std::lround((band.frequency_hz[0] - all.frequency_hz[0]) / df));
  for (int i = 0; i < band.LineCount(); ++i) EXPECT_EQ(band.h[0](i, 0), all.h[0](first + i, 0)) << i;
}

TEST_F(FrfCli, QuantityMobilityDividesAccelerancebyJOmega) {
  plan_.roving_sets = {{{1, 3}}};
  plan_.samples_per_record = 2048;
  Write(plan_, {"a.unv"});
  ASSERT_EQ(RunEma("frf " + P("a.unv") + " -o " + P("acc.unv"), dir_).code, 0);
  ASSERT_EQ(RunEma("frf " + P("a.unv") + " -o " + P("mob.unv") + " --quantity mobility", dir_).code, 0);
  const FrfSet acc = formats::ReadFrfSet(dir_ / "acc.unv"), mob = formats::ReadFrfSet(dir_ / "mob.unv");
  EXPECT_EQ(mob.output_quantity, Quantity::kVelocity);
  EXPECT_EQ(acc.output_quantity, Quantity::kAcceleration);
  ASSERT_EQ(mob.LineCount(), acc.LineCount());
  for (int i = 1; i < acc.LineCount(); i += 37) {
    const std::complex<double> jw(0.0, kTwoPi * acc.frequency_hz[i]);
    // Two 6-digit ASCII values: 2e-5 relative.
    EXPECT_LT(std::abs(mob.h[0](i, 0) - acc.h[0](i, 0) / jw), 2e-5 * std::abs(acc.h[0](i, 0) / jw)) << "line " << i;
  }
}

TEST_F(FrfCli, ThreadsDoNotChangeTheResultAndAreValidated) {
  plan_.roving_sets = {{{1, 3}, {2, 3}, {3, 3}}};
  plan_.samples_per_record = 2048;
  Write(plan_, {"a.unv"});
  ASSERT_EQ(RunEma("frf " + P("a.unv") + " -o " + P("t1.unv") + " --threads 1", dir_).code, 0);
  ASSERT_EQ(RunEma("frf " + P("a.unv") + " -o " + P("t2.unv") + " --threads 2", dir_).code, 0);
  // Compared as values: the files' headers carry the time of writing.
  const FrfSet t1 = formats::ReadFrfSet(dir_ / "t1.unv"), t2 = formats::ReadFrfSet(dir_ / "t2.unv");
  ASSERT_EQ(t1.OutputCount(), 3);
  for (int o = 0; o < 3; ++o) {
    EXPECT_TRUE(t1.h[0].col(o) == t2.h[0].col(o)) << "per-FRF ownership: the thread count must not change a digit";
    EXPECT_TRUE(t1.coherence[0].col(o) == t2.coherence[0].col(o));
  }
  EXPECT_EQ(RunEma("frf " + P("a.unv") + " -o " + P("t0.unv") + " --threads -3", dir_).code, 2);
}

TEST_F(FrfCli, ExponentialWindowRateIsAppliedAndRecorded) {
  // A 20 1/s window adds 20/ω to each mode's apparent damping: at the 40 Hz mode (ζ = 1 %, so
  // σ = ζω ≈ 2.5 1/s) the peak falls to about 2.5/(2.5+20) ≈ 0.11 of the unwindowed one.
  plan_.roving_sets = {{{1, 3}}};
  Write(plan_, {"a.unv"});
  ASSERT_EQ(RunEma("frf " + P("a.unv") + " -o " + P("none.unv") + " --exp-window none --json " + P("none.json"), dir_).code, 0);
  ASSERT_EQ(RunEma("frf " + P("a.unv") + " -o " + P("w.unv") + " --exp-window 20 --json " + P("w.json"), dir_).code, 0);
  const FrfSet none = formats::ReadFrfSet(dir_ / "none.unv"), w = formats::ReadFrfSet(dir_ / "w.unv");
  EXPECT_EQ(none.window_decay_rate, 0.0);
  EXPECT_DOUBLE_EQ(w.window_decay_rate, 20.0);
  std::ifstream in(dir_ / "w.json");
  EXPECT_DOUBLE_EQ(nlohmann::json::parse(in).at("window_decay_rate").get<double>(), 20.0);
  const double df = none.frequency_hz[1] - none.frequency_hz[0];
  const int peak = static_cast<int>(std::lround(sys_.frequency_hz[0] / df));
  double p_none = 0.0, p_w = 0.0;
  for (int i = peak - 2; i <= peak + 2; ++i) {
    p_none = std::max(p_none, std::abs(none.h[0](i, 0)));
    p_w = std::max(p_w, std::abs(w.h[0](i, 0)));
  }
  const double sigma = sys_.damping[0] * kTwoPi * sys_.frequency_hz[0];
  // ±30 %: the line grid (0.5 Hz) samples the peaks at slightly different offsets.
  EXPECT_NEAR(p_w / p_none, sigma / (sigma + 20.0), 0.3 * sigma / (sigma + 20.0));
}

TEST_F(FrfCli, ForceWindowKeepsForceNoiseOutOfH1) {
  // 5 % force noise over a 2 s record: without a force window the noise after the pulse adds to
  // Gff and biases H1 low; the default window (3 contact times after the pulse) removes it.
  plan_.roving_sets = {{{1, 3}}};
  plan_.force_noise = 0.05;
  plan_.response_noise = 0.0;
  Write(plan_, {"a.unv"});
  ASSERT_EQ(RunEma("frf " + P("a.unv") + " -o " + P("win.unv"), dir_).code, 0);
  ASSERT_EQ(RunEma("frf " + P("a.unv") + " -o " + P("wide.unv") + " --force-window 100000", dir_).code, 0);
  const FrfSet win = formats::ReadFrfSet(dir_ / "win.unv"), wide = formats::ReadFrfSet(dir_ / "wide.unv");
  const Eigen::VectorXcd truth = acquisition::AnalyticFrf(sys_.truth, win.outputs[0], win.references[0], win.frequency_hz);
  double err_win = 0.0, err_wide = 0.0, coh_win = 0.0, coh_wide = 0.0;
  for (int i = 10; i < win.LineCount() / 2; ++i) {
    err_win += std::abs(win.h[0](i, 0) - truth[i]) / std::abs(truth[i]);
    err_wide += std::abs(wide.h[0](i, 0) - truth[i]) / std::abs(truth[i]);
    coh_win += win.coherence[0](i, 0);
    coh_wide += wide.coherence[0](i, 0);
  }
  EXPECT_LT(err_win, 0.5 * err_wide) << "the force window must at least halve the mean error";
  EXPECT_GT(coh_win, coh_wide);
}

TEST_F(FrfCli, AcceptDoubleHitsKeepsTheImpact) {
  plan_.roving_sets = {{{2, 3}}};
  plan_.samples_per_record = 2048;
  plan_.double_hits.push_back({0, 0, 3, 3e-3, 0.3});
  Write(plan_, {"a.unv"});
  auto averages = [&](const std::string& extra) {
    EXPECT_EQ(RunEma("frf " + P("a.unv") + " -o " + P("o.unv") + " --json " + P("s.json") + extra, dir_).code, 0);
    std::ifstream in(dir_ / "s.json");
    const nlohmann::json j = nlohmann::json::parse(in);
    return std::make_pair(j["frfs"][0]["averages"].get<int>(), j["frfs"][0]["rejected"].size());
  };
  EXPECT_EQ(averages(""), std::make_pair(4, size_t{1}));
  EXPECT_EQ(averages(" --accept-double-hits"), std::make_pair(5, size_t{0}));
}

TEST_F(FrfCli, TriggerLevelMovesTheRecordStart) {
  // The records are aligned on the trigger crossing: a higher level crosses later on the rising
  // half-sine, which shifts both channels alike. The FRF's magnitude stays (within the noise) but
  // the written values change, so an ignored option shows.
  plan_.roving_sets = {{{2, 3}}};
  plan_.samples_per_record = 2048;
  Write(plan_, {"a.unv"});
  ASSERT_EQ(RunEma("frf " + P("a.unv") + " -o " + P("lo.unv") + " --trigger-level 0.05", dir_).code, 0);
  ASSERT_EQ(RunEma("frf " + P("a.unv") + " -o " + P("hi.unv") + " --trigger-level 0.9", dir_).code, 0);
  EXPECT_EQ(RunEma("frf " + P("a.unv") + " -o " + P("x.unv") + " --trigger-level 1.5", dir_).code, 2);
  const FrfSet lo = formats::ReadFrfSet(dir_ / "lo.unv"), hi = formats::ReadFrfSet(dir_ / "hi.unv");
  bool changed = false;
  for (double f : sys_.frequency_hz) {
    const int i = static_cast<int>(std::lround(f / (lo.frequency_hz[1] - lo.frequency_hz[0])));
    changed = changed || lo.h[0](i, 0) != hi.h[0](i, 0);
    // 0.5 % noise, 5 averages: the two alignments agree on |H| at the resonances within 2 %.
    EXPECT_LT(std::abs(std::abs(hi.h[0](i, 0)) - std::abs(lo.h[0](i, 0))), 0.02 * std::abs(lo.h[0](i, 0))) << f;
  }
  EXPECT_TRUE(changed);
}

}  // namespace
}  // namespace ema

namespace ema {
namespace {

TEST_F(FrfCli, ForceBinsSplitImpactsByPeakForceIntoOneFrfSetPerBin) {
  // Three force levels of 4 impacts each (spread ±10 %) in one file: 3 equal-count bins hold
  // one level each, and every bin's FRF is the linear truth's.
  acquisition::HammerTestPlan plan = plan_;
  plan.roving_sets = {{{1, 3}, {2, 3}, {3, 3}}};
  plan.impacts_per_reference = 4;
  plan.force_levels_n = {10.0, 40.0, 160.0};
  Write(plan, {"levels.unv"});
  const RunResult r = RunEma("frf " + P("levels.unv") + " -o " + P("frf.unv") + " --force-bins 3 --json " + P("s.json"), dir_);
  ASSERT_EQ(r.code, 0) << r.err;
  std::ifstream in(dir_ / "s.json");
  const nlohmann::json j = nlohmann::json::parse(in);
  ASSERT_EQ(j["bins"].size(), 3u);
  const double nominal[3] = {10.0, 40.0, 160.0};
  for (int b = 0; b < 3; ++b) {
    const nlohmann::json& bin = j["bins"][b];
    EXPECT_EQ(bin["bin"], b + 1);
    EXPECT_EQ(bin["impacts"], 4);
    EXPECT_EQ(bin["file"], (dir_ / ("frf.bin" + std::to_string(b + 1) + ".unv")).string());
    // The sampled peak of a 1 ms half-sine at 4096 Hz is within 10 % spread + a few % of the
    // nominal level (the sample misses the crest by up to half a sample).
    EXPECT_NEAR(bin["level"].get<double>(), nominal[b], 0.15 * nominal[b]);
    // A half-sine's RMS over its contact is peak/√2; sampled with 4 points per pulse: 20 %.
    EXPECT_NEAR(bin["rms_force_n"].get<double>(), nominal[b] / std::sqrt(2.0), 0.2 * nominal[b] / std::sqrt(2.0));
    const FrfSet set = formats::ReadFrfSet(bin["file"].get<std::string>());
    ASSERT_EQ(set.outputs.size(), 3u);
    const Eigen::VectorXcd truth = acquisition::AnalyticFrf(sys_.truth, {2, 3}, {1, 3}, set.frequency_hz);
    // Near the first mode (40 Hz) the H1 estimate from 4 impacts at 0.5 % noise is within 3 %.
    for (Eigen::Index k = 0; k < set.frequency_hz.size(); ++k) {
      if (std::abs(set.frequency_hz[k] - sys_.frequency_hz[0]) < 1.0) {
        EXPECT_NEAR(std::abs(set.h[0](k, 1)), std::abs(truth[k]), 0.03 * std::abs(truth[k])) << set.frequency_hz[k];
      }
    }
  }
  EXPECT_EQ(j["frfs"].size(), 9u);  // 3 FRFs per bin, each tagged with its bin
  EXPECT_EQ(j["frfs"][8]["bin"], 3);
  EXPECT_FALSE(fs::exists(dir_ / "frf.unv"));  // bins only

  // Explicit edges: the lowest level left out.
  const RunResult e = RunEma("frf " + P("levels.unv") + " -o " + P("e.unv") + " --force-bin-edges 20,80,300 --json " + P("e.json"), dir_);
  ASSERT_EQ(e.code, 0) << e.err;
  std::ifstream ein(dir_ / "e.json");
  const nlohmann::json ej = nlohmann::json::parse(ein);
  ASSERT_EQ(ej["bins"].size(), 2u);
  EXPECT_EQ(ej["left_out_impacts"], 4);
  EXPECT_NEAR(ej["bins"][0]["level"].get<double>(), 40.0, 6.0);

  // Bad usage and empty bins.
  EXPECT_EQ(RunEma("frf " + P("levels.unv") + " -o " + P("x.unv") + " --force-bins 0", dir_).code, 2);
  EXPECT_EQ(RunEma("frf " + P("levels.unv") + " -o " + P("x.unv") + " --force-bin-edges 5", dir_).code, 2);
  EXPECT_EQ(RunEma("frf " + P("levels.unv") + " -o " + P("x.unv") + " --force-bins 2 --force-bin-edges 1,2", dir_).code, 2);
  const RunResult empty = RunEma("frf " + P("levels.unv") + " -o " + P("x.unv") + " --force-bin-edges 1,2,500", dir_);
  EXPECT_EQ(empty.code, 1);
  EXPECT_THAT(empty.err, HasSubstr("holds no impact"));
  EXPECT_FALSE(fs::exists(dir_ / "x.bin1.unv"));
}

}  // namespace
}  // namespace ema
