// `ema fit` on a two-set roving test of a light FE beam (tests/curvefit/data/two-set-beam): the
// sets' sensors load the beam differently (8 × 10 g against 5 × 10 g), so each mode sits 0.5–3.5 %
// apart in the two sets. Every mode of the band must be found and each set fitted with its own
// poles: set 1's frequencies then equal those a test with set 1 alone gives.
#include <gtest/gtest.h>

#include <filesystem>
#include <cmath>
#include <fstream>
#include <string>

#include <nlohmann/json.hpp>

#include "test_files.hpp"

namespace {

namespace fs = std::filesystem;

// The truth and the plan of the two-set test (README.md beside them).
fs::path Data() { return fs::path(EMA_SOURCE_DIR) / "tests/curvefit/data/two-set-beam"; }

// The truth tested with `plan` (ema simulate, frf, fit over the first test's band) in `dir`: MODES.json.
nlohmann::json FitToJson(const fs::path& plan, const fs::path& dir) {
  fs::remove_all(dir);
  fs::create_directories(dir);
  const auto in = [&](const char* name) { return "'" + (dir / name).string() + "'"; };
  EXPECT_EQ(ema::test::RunEma("simulate '" + (Data() / "simulate.toml").string() + "' --plan '" + plan.string() +
                                  "' -o " + in("time.unv") + " --binary",
                              dir),
            0)
      << ema::test::Slurp(dir / "stderr.txt");
  EXPECT_EQ(ema::test::RunEma("frf " + in("time.unv") + " -o " + in("frf.unv"), dir), 0)
      << ema::test::Slurp(dir / "stderr.txt");
  EXPECT_EQ(ema::test::RunEma("fit " + in("frf.unv") + " -o " + in("modes.unv") + " --band 34:842.5 --json " +
                                  in("modes.json"),
                              dir),
            0)
      << ema::test::Slurp(dir / "stderr.txt");
  std::ifstream file(dir / "modes.json");
  return nlohmann::json::parse(file);
}

TEST(TwoSetBeam, EveryModeIsFoundAndEachSetGetsItsOwnPoles) {
  const fs::path data = Data();
  const fs::path tmp = fs::path(EMA_TEST_TMP_DIR) / "two_set_beam";
  // The first test: set 1 of the plan alone (replan.toml without its added set 2).
  fs::create_directories(tmp);
  {
    std::ifstream full(data / "replan.toml");
    std::ofstream first(tmp / "first-set.toml");
    std::string line;
    while (std::getline(full, line) && line != "[[set]]") first << line << '\n';
    first << "[[set]]\n";
    std::getline(full, line);
    first << line << '\n';
    std::getline(full, line);
    first << line << '\n';
  }
  const nlohmann::json one = FitToJson(tmp / "first-set.toml", tmp / "one");
  const nlohmann::json two = FitToJson(data / "replan.toml", tmp / "two");
  ASSERT_EQ(one["modes"].size(), 6u) << one["modes"].dump();
  // Before the fragments of a drifting column were joined, the automatic selection kept 3 of the 6
  // (63, 127 and 257 Hz were cut into pieces each shorter than the span test) and every refinement
  // was rejected (misfit ~3000× the noise).
  ASSERT_EQ(two["modes"].size(), 6u) << two["modes"].dump();
  EXPECT_NE(two["refinement"]["message"].get<std::string>().find("each of 2 roving sets fitted with its own poles"),
            std::string::npos)
      << two["refinement"].dump();
  for (size_t k = 0; k < 6; ++k) {
    const auto& sets = two["modes"][k]["sets"];
    ASSERT_EQ(sets.size(), 2u) << k;
    // Set 1 is the first test's data simulated alike: its frequency within 0.01 % of the one-set
    // fit's (their σ is ≤ 1e-5 relative), while the sets differ by 0.37–3.4 % from each other.
    const double f_one = one["modes"][k]["frequency_hz"].get<double>();
    EXPECT_NEAR(sets[0]["frequency_hz"].get<double>(), f_one, 1e-4 * f_one) << k;
    EXPECT_GT(std::abs(sets[1]["frequency_hz"].get<double>() - f_one), 3e-3 * f_one) << k;
  }
}

// The two-set test with 2.5 g sensors and, when `samples` > 0, that many samples per record, fitted
// in its own folder `name` under the test build's tmp: MODES.json.
nlohmann::json FitLightSensorTest(const char* name, int samples) {
  const fs::path tmp = fs::path(EMA_TEST_TMP_DIR) / name;
  fs::create_directories(tmp);
  {
    std::ifstream full(Data() / "replan.toml");
    std::ofstream light(tmp / "plan.toml");
    std::string line;
    while (std::getline(full, line))
      light << (line.rfind("sensor_mass", 0) == 0                     ? "sensor_mass = 0.0025"
                : samples > 0 && line.rfind("samples", 0) == 0 ? "samples = " + std::to_string(samples)
                                                                : line)
            << '\n';
  }
  return FitToJson(tmp / "plan.toml", tmp / "two");
}

int DroppedAsSetTwins(const nlohmann::json& fit, const std::string& how) {
  int n = 0;
  for (const auto& d : fit["dropped"]) {
    const std::string reason = d["reason"].get<std::string>();
    n += reason.find("the roving sets see it at slightly different frequencies") != std::string::npos &&
         reason.find(how) != std::string::npos;
  }
  return n;
}

// The same test with 2.5 g sensors: each mode sits only 0.1–0.9 % apart in the two sets, so close
// that one mode's two columns in the stabilisation diagram both last and their shapes blend over
// both sets' outputs (the split-pole rule, which looks for shapes on different outputs, keeps
// both). Two poles for one mode leave each set's refinement pressed against a neighbour; with the
// weaker dropped, every set fits with its own poles. Before: 7 modes, the refinement rejected.
TEST(TwoSetBeam, OneModeSeenAsTwoClosePolesIsFittedAsOne) {
  const nlohmann::json two = FitLightSensorTest("two_set_beam_light", 0);
  ASSERT_EQ(two["modes"].size(), 6u) << two["modes"].dump();
  EXPECT_NE(two["refinement"]["message"].get<std::string>().find("each of 2 roving sets fitted with its own poles"),
            std::string::npos)
      << two["refinement"].dump();
  EXPECT_GE(DroppedAsSetTwins(two, "every set's own refinement fits"), 1) << two["dropped"].dump();
  for (const auto& mode : two["modes"]) {
    ASSERT_EQ(mode["sets"].size(), 2u);
    // The sets' own frequencies: apart (0.1–0.9 % here, each set's 2.5 g sensors where they are;
    // their σ is ≤ 1e-5 relative), and not by more than such light sensors can move a mode.
    const double f1 = mode["sets"][0]["frequency_hz"].get<double>(), f2 = mode["sets"][1]["frequency_hz"].get<double>();
    EXPECT_GT(std::abs(f2 / f1 - 1.0), 5e-4) << mode.dump();
    EXPECT_LT(std::abs(f2 / f1 - 1.0), 1.5e-2) << mode.dump();
  }
}

// The same light-sensor test with records of 0.5 s (2048 samples): the 46 Hz mode has not decayed,
// the leakage leaves a misfit no modal model removes, and the misfit test rejects every refinement
// — so no drop can make the sets' refinement pass it. The twins still pull a set's pole against its
// neighbour's edge; with one dropped every set's poles stay in place, and that decides (before: 7
// modes, 788 Hz twice). Then each set keeps the poles it saw, the misfit said (before: one pole per
// mode, the PolyMAX pole of one set, while the sets see the modes 0.1–0.9 % apart).
TEST(TwoSetBeam, TwinPolesAreDroppedAlsoWhereTheBandsMisfitRejectsEveryRefinement) {
  const nlohmann::json two = FitLightSensorTest("two_set_beam_short", 2048);
  ASSERT_EQ(two["modes"].size(), 6u) << two["modes"].dump();
  EXPECT_GE(DroppedAsSetTwins(two, "every set's refined poles stay in place"), 1) << two["dropped"].dump();
  const std::string summary = two["refinement"]["message"].get<std::string>();
  EXPECT_NE(summary.find("each of 2 roving sets fitted with its own poles"), std::string::npos) << summary;
  EXPECT_NE(summary.find("above the noise: each set keeps the frequencies it saw"), std::string::npos) << summary;
  // What the same sets give with 2 s records (the fit of OneModeSeenAsTwoClosePolesIsFittedAsOne):
  // each set's frequency within 0.2 % (the leakage biases the undecayed 46 Hz mode by 0.1 %), and the
  // gap between the sets — the leakage moves both alike — within 35 % of its own, sign included
  // (measured 2026-11-30: within 22 %), so sets swapped or merged fail.
  const double set1_hz[] = {46.063, 64.900, 128.735, 262.923, 485.577, 787.858};
  const double set2_hz[] = {46.218, 65.465, 128.404, 262.661, 486.945, 790.147};
  for (size_t k = 0; k < 6; ++k) {
    const auto& sets = two["modes"][k]["sets"];
    ASSERT_EQ(sets.size(), 2u) << k;
    const double f1 = sets[0]["frequency_hz"].get<double>(), f2 = sets[1]["frequency_hz"].get<double>();
    EXPECT_NEAR(f1, set1_hz[k], 2e-3 * set1_hz[k]) << k;
    EXPECT_NEAR(f2, set2_hz[k], 2e-3 * set2_hz[k]) << k;
    const double gap = set2_hz[k] - set1_hz[k];
    EXPECT_NEAR(f2 - f1, gap, 0.35 * std::abs(gap)) << k;
  }
}

}  // namespace
