// The readers beside the CLI that the Python package shares with it (formats/modes_sidecar.hpp,
// formats/output_guard.hpp): a modes file's `ema fit --json` sidecar, the mode sets per level and
// their messages (the words of cli::ParseNumber), and the outputs-never-replace-inputs guard.
// The commands themselves: tests/app (amplitude_cli_test, outputs_spare_inputs_test).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "ema/core/error.hpp"
#include "ema/formats/io.hpp"
#include "ema/formats/json_codecs.hpp"
#include "ema/formats/modes_sidecar.hpp"
#include "ema/formats/output_guard.hpp"
#include "tmp_file.hpp"

namespace ema::formats {
namespace {

namespace fs = std::filesystem;

// Two modes at DOFs 1+Z, 2+Z, written as MODES.unv into `dir`, with (when `with_sidecar`) the
// `ema fit --json` file beside it carrying each mode's σ and the test's roving sets.
fs::path WriteSidecarModes(const std::string& dir, bool with_sidecar) {
  const fs::path folder = test::TmpFile(dir);
  fs::remove_all(folder);
  fs::create_directories(folder);
  ModeSet set;
  set.dofs = {{1, 3}, {2, 3}};
  for (double f : {100.0, 250.0}) {
    Mode m;
    m.frequency_hz = f;
    m.damping_ratio = 0.01;
    m.shape = Eigen::VectorXcd::Ones(2);
    set.modes.push_back(m);
  }
  const fs::path unv = folder / "modes.unv";
  WriteModeSet(unv, set);
  if (with_sidecar) {
    nlohmann::json j = ModeSetJson(set);
    for (std::size_t i = 0; i < j["modes"].size(); ++i) {
      j["modes"][i]["frequency_std_hz"] = 0.5 * static_cast<double>(i + 1);
      j["modes"][i]["damping_ratio_std"] = 0.001;
    }
    j["roving_sets"] = nlohmann::json::array({nlohmann::json::array({1}), nlohmann::json::array({2})});
    j["reference"] = {{"node", 1}, {"dir", DirectionName(3)}};
    std::ofstream(folder / "modes.json") << j.dump();
  }
  return unv;
}

std::string LevelsError(const std::vector<std::string>& args) {
  try {
    ReadAmplitudeLevels(args, "--level");
  } catch (const UsageError& e) {
    return std::string("usage: ") + e.what();
  } catch (const InputError& e) {
    return std::string("input: ") + e.what();
  }
  return "no error";
}

TEST(ModesSidecar, TheSidecarGivesEachModeItsSigmaAndTheRovingSets) {
  const fs::path unv = WriteSidecarModes("sidecar-with", true);
  ModeSet modes = ReadModeSet(unv);
  AttachSidecarUncertainty(unv.string(), &modes);
  ASSERT_EQ(modes.modes.size(), 2u);
  EXPECT_DOUBLE_EQ(modes.modes[0].frequency_std_hz, 0.5);
  EXPECT_DOUBLE_EQ(modes.modes[1].frequency_std_hz, 1.0);
  EXPECT_DOUBLE_EQ(modes.modes[1].damping_ratio_std, 0.001);
  std::vector<std::vector<int>> sets;
  Dof reference;
  ASSERT_TRUE(ReadSidecarTestSets(unv.string(), modes, &sets, &reference));
  EXPECT_EQ(sets, (std::vector<std::vector<int>>{{1}, {2}}));
  EXPECT_EQ(reference.node, 1);
  EXPECT_EQ(reference.direction, 3);

  const std::vector<correlation::AmplitudeLevel> levels = ReadAmplitudeLevels({"2.5=" + unv.string()}, "--level");
  ASSERT_EQ(levels.size(), 1u);
  EXPECT_DOUBLE_EQ(levels[0].level, 2.5);
  ASSERT_EQ(levels[0].uncertainty.size(), 2u);
  EXPECT_DOUBLE_EQ(levels[0].uncertainty[1].frequency_std_hz, 1.0);
  EXPECT_EQ(AmplitudeLevelFiles({"2.5=" + unv.string(), "bad"}), std::vector<std::string>{unv.string()});
}

TEST(ModesSidecar, WithoutASidecarNothingIsAdded) {
  const fs::path unv = WriteSidecarModes("sidecar-without", false);
  ModeSet modes = ReadModeSet(unv);
  AttachSidecarUncertainty(unv.string(), &modes);
  EXPECT_FALSE(std::isfinite(modes.modes[0].frequency_std_hz));
  std::vector<std::vector<int>> sets;
  Dof reference;
  EXPECT_FALSE(ReadSidecarTestSets(unv.string(), modes, &sets, &reference));
  EXPECT_TRUE(ReadAmplitudeLevels({"1=" + unv.string()}, "--level")[0].uncertainty.empty());
}

// The messages of `ema amplitude --level` / `ema diagnose --force-level` (cli.md): a level is a
// finite number as cli::ParseNumber reads one (std::stod, the whole text), and > 0.
TEST(ModesSidecar, BadLevelsAreUsageErrorsWithTheCommandLinesWords) {
  const std::string unv = WriteSidecarModes("sidecar-levels", false).string();
  EXPECT_EQ(LevelsError({"modes.unv"}), "usage: --level expects LEVEL=MODES.unv, got 'modes.unv'");
  EXPECT_EQ(LevelsError({"=" + unv}), "usage: --level expects LEVEL=MODES.unv, got '=" + unv + "'");
  EXPECT_EQ(LevelsError({"2="}), "usage: --level expects LEVEL=MODES.unv, got '2='");
  for (const std::string level : {"abc", "1e400", "1e-400", "inf", "nan", "2 ", "1,5", "3N"})
    EXPECT_EQ(LevelsError({level + "=" + unv}), "usage: --level: expected a number, got '" + level + "'") << level;
  EXPECT_EQ(LevelsError({"0=" + unv}), "usage: --level: level must be > 0, got '0'");
  EXPECT_EQ(LevelsError({"-2=" + unv}), "usage: --level: level must be > 0, got '-2'");
  EXPECT_EQ(LevelsError({" 2=" + unv, "0x10=" + unv, "+.5=" + unv}), "no error");
  EXPECT_EQ(LevelsError({"1=" + unv, "2=missing.unv"}), "input: missing.unv: mode file not found");
}

std::string GuardError(const std::vector<PathArg>& inputs, const std::vector<PathArg>& outputs) {
  try {
    RefuseOutputsOverInputs(inputs, outputs);
  } catch (const UsageError& e) {
    return e.what();
  }
  return "no error";
}

TEST(OutputGuard, AnOutputOverAnInputOrAFileItNamesIsRefused) {
  const fs::path folder = test::TmpFile("output-guard");
  fs::remove_all(folder);
  fs::create_directories(folder);
  std::ofstream(folder / "curve.csv") << "0,0\n1,1\n";
  std::ofstream(folder / "model.toml") << "curve = \"curve.csv\"\n";
  const std::string model = (folder / "model.toml").string(), curve = (folder / "curve.csv").string();
  EXPECT_EQ(GuardError({{"model", model}}, {{"-o", (folder / "." / "model.toml").string()}}),
            "-o " + (folder / "." / "model.toml").string() + ": refused, it would replace the input " + model +
                " (outputs never replace inputs: choose another output name)");
  EXPECT_EQ(GuardError({{"--model", model}}, {{"--json", curve}}),
            "--json " + curve + ": refused, it would replace '" + curve + "', which the input --model " + model +
                " names (outputs never replace inputs: choose another output name)");
  const std::string out = (folder / "out.json").string();
  EXPECT_EQ(GuardError({{"model", model}}, {{"-o", out}, {"--json", out}}),
            "--json " + out + ": refused, -o " + out + " writes the same file");
  EXPECT_EQ(GuardError({{"model", model}, {"keep", ""}}, {{"-o", out}, {"--json", ""}}), "no error");
}

}  // namespace
}  // namespace ema::formats
