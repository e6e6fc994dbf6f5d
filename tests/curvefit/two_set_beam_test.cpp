// `ema fit` on a two-set roving test whose fit goes wrong (tests/curvefit/data/two-set-beam): the
// sets' own refinement is not usable, and the fit must say why, not only that the one-pole
// refinement that replaced it was rejected too.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "test_files.hpp"

namespace {

namespace fs = std::filesystem;

TEST(TwoSetBeam, TheFitSaysWhyTheRovingSetsGotNoPolesOfTheirOwn) {
  const fs::path data = fs::path(EMA_SOURCE_DIR) / "tests/curvefit/data/two-set-beam";
  const fs::path dir = fs::path(EMA_TEST_TMP_DIR) / "two_set_beam";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const auto in = [&](const char* name) { return "'" + (dir / name).string() + "'"; };
  ASSERT_EQ(ema::test::RunEma("simulate '" + (data / "simulate.toml").string() + "' --plan '" +
                                  (data / "replan.toml").string() + "' -o " + in("time.unv") + " --binary",
                              dir),
            0)
      << ema::test::Slurp(dir / "stderr.txt");
  ASSERT_EQ(ema::test::RunEma("frf " + in("time.unv") + " -o " + in("frf.unv"), dir), 0) << ema::test::Slurp(dir / "stderr.txt");
  ASSERT_EQ(ema::test::RunEma("fit " + in("frf.unv") + " -o " + in("modes.unv") + " --band 34:842.5", dir), 0)
      << ema::test::Slurp(dir / "stderr.txt");
  const std::string said = ema::test::Slurp(dir / "stderr.txt");
  // The one-pole refinement's own rejection, and — what was silent before — the sets' reason.
  EXPECT_NE(said.find("ML refinement: rejected"), std::string::npos) << said;
  EXPECT_NE(said.find("one pole per mode for every roving set (roving set "), std::string::npos) << said;
}

}  // namespace
