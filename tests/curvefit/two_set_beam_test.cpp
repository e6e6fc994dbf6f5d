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

nlohmann::json FitToJson(const fs::path& simulate, const fs::path& plan, const fs::path& dir) {
  fs::remove_all(dir);
  fs::create_directories(dir);
  const auto in = [&](const char* name) { return "'" + (dir / name).string() + "'"; };
  EXPECT_EQ(ema::test::RunEma("simulate '" + simulate.string() + "' --plan '" + plan.string() + "' -o " +
                                  in("time.unv") + " --binary",
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
  const fs::path data = fs::path(EMA_SOURCE_DIR) / "tests/curvefit/data/two-set-beam";
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
  const nlohmann::json one = FitToJson(data / "simulate.toml", tmp / "first-set.toml", tmp / "one");
  const nlohmann::json two = FitToJson(data / "simulate.toml", data / "replan.toml", tmp / "two");
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

}  // namespace
