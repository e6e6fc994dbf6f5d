// The bolted-frame sample (samples/bolted-frame, issue 27): part matrices from the real FE code
// CalculiX, a simulated roving-hammer test of the truth with joint J3 at 30 % of its stiffness,
// and `ema run` naming that joint at rank 1 with its factor.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "browser_check.hpp"
#include "golden.hpp"
#include "test_files.hpp"

namespace ema {
namespace {

namespace fs = std::filesystem;

int RunShell(const std::string& command, const fs::path& log) {
  const int status = std::system((command + " > '" + log.string() + "' 2>&1").c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

using test::Slurp;

TEST(SampleBoltedFrame, RunNamesTheLoosenedJointFromCalculixParts) {
  if (std::system("command -v ccx > /dev/null 2>&1") != 0) {
    if (!test::BrowserCheckMayBeSkipped()) FAIL() << "ccx missing in CI (scripts/install-deps.sh installs calculix-ccx)";
    GTEST_SKIP() << "CalculiX (ccx) not installed: scripts/install-deps.sh";
  }
  const fs::path dir = fs::path(EMA_TEST_TMP_DIR) / "bolted-frame";
  fs::remove_all(dir);
  const std::string python = fs::exists("/usr/bin/python3") ? "/usr/bin/python3" : "python3";  // Debian's, with numpy
  ASSERT_EQ(RunShell(python + " '" + EMA_SOURCE_DIR + "/samples/bolted-frame/make_sample.py' --out '" + dir.string() +
                         "' --ema '" + EMA_EXECUTABLE + "'",
                dir.string() + "-make.log"),
            0)
      << Slurp(dir.string() + "-make.log");
  const std::string ema = EMA_EXECUTABLE;
  ASSERT_EQ(RunShell(ema + " simulate '" + (dir / "truth-model.toml").string() + "' --plan '" + (dir / "plan.toml").string() +
                    "' -o '" + (dir / "time.unv").string() + "' --binary",
                dir.string() + "-simulate.log"),
            0)
      << Slurp(dir.string() + "-simulate.log");
  ASSERT_EQ(RunShell(ema + " run '" + (dir / "project.toml").string() + "' -o '" + (dir / "out").string() + "' --no-report",
                dir.string() + "-run.log"),
            0)
      << Slurp(dir.string() + "-run.log");
  const nlohmann::json d = nlohmann::json::parse(Slurp(dir / "out" / "diagnosis.json"));
  const nlohmann::json& first = d["candidates"][0];
  const std::string summary = Slurp(dir / "out" / "summary.txt");
  ASSERT_EQ(first["effects"].size(), 1u) << summary;
  EXPECT_EQ(first["kind"], "stiffness_scale") << summary;
  EXPECT_EQ(first["target"], "joints/J3") << summary;
  EXPECT_NEAR(first["parameters"]["factor"].get<double>() / 0.3, 1.0, 0.10) << first.dump();
  EXPECT_GT(first["probability"].get<double>(), 0.9) << summary;
  // The numbers of the run before it was one typed pipeline (issue 38): the same ranking, the same
  // evidence per mode, the same fitted modes.
  const nlohmann::json golden =
      nlohmann::json::parse(Slurp(fs::path(EMA_SOURCE_DIR) / "tests/data/golden/bolted-frame-run.json"));
  int compared = 0;
  test::ExpectSameNumbers(golden["diagnosis"], d, "diagnosis", &compared);
  test::ExpectSameNumbers(golden["modes"]["hammer"], nlohmann::json::parse(Slurp(dir / "out" / "hammer" / "modes.json")),
                          "modes", &compared);
  EXPECT_GT(compared, 300);
  // The updated model agrees with the test.
  const nlohmann::json after = nlohmann::json::parse(Slurp(dir / "out" / "hammer" / "correlation-after.json"));
  EXPECT_GE(after["summary"]["mean_agreement_pct"].get<double>(), 99.0);

  // `ema plan` for the sample with its five triaxial accelerometers (issue 40): three sets of 15 of
  // the 18 test points, two hammer DOFs — every mode of the band seen apart (AutoMAC <= 0.1) and
  // excited; the truth tested with that plan, fitted, gives back every target mode.
  ASSERT_EQ(RunShell(ema + " plan '" + (dir / "model.toml").string() + "' --triaxial --sensors 5 --sets 3 --references 2 "
                         "--band 20:305 -o '" + (dir / "plan-ema.toml").string() + "' --json '" +
                         (dir / "plan-ema.json").string() + "'",
                     dir.string() + "-plan.log"),
            0)
      << Slurp(dir.string() + "-plan.log");
  const nlohmann::json plan = nlohmann::json::parse(Slurp(dir / "plan-ema.json"));
  EXPECT_LE(plan["automac_max_offdiagonal"].get<double>(), 0.1);
  ASSERT_EQ(plan["modes"].size(), 8u) << plan.dump();
  for (const auto& m : plan["modes"]) EXPECT_TRUE(m["excited"].get<bool>()) << m.dump();
  for (const auto& [step, command] : std::vector<std::pair<std::string, std::string>>{
           {"simulate", "simulate '" + (dir / "truth-model.toml").string() + "' --plan '" + (dir / "plan-ema.toml").string() +
                            "' -o '" + (dir / "time-plan.unv").string() + "' --binary"},
           {"frf", "frf '" + (dir / "time-plan.unv").string() + "' -o '" + (dir / "frf-plan.unv").string() + "'"},
           {"fit", "fit '" + (dir / "frf-plan.unv").string() + "' -o '" + (dir / "modes-plan.unv").string() + "' --band 20:305"},
           {"correlate", "correlate '" + (dir / "modes-plan.unv").string() + "' '" + (dir / "truth-model.toml").string() +
                             "' --json '" + (dir / "corr-plan.json").string() + "'"}})
    ASSERT_EQ(RunShell(ema + " " + command, dir.string() + "-" + step + "-plan.log"), 0)
        << step << ": " << Slurp(dir.string() + "-" + step + "-plan.log");
  const nlohmann::json corr = nlohmann::json::parse(Slurp(dir / "corr-plan.json"));
  ASSERT_EQ(corr["pairs"].size(), 8u) << corr.dump();
  for (size_t i = 0; i < 8; ++i) {
    const auto& pair = corr["pairs"][i];
    EXPECT_EQ(pair["model_mode"].get<int>(), static_cast<int>(i) + 1) << pair.dump();
    EXPECT_GE(pair["mac"].get<double>(), 0.99) << pair.dump();
    // The plan's sensor mass is 0: the truth's own frequencies within the fit's noise.
    EXPECT_NEAR(pair["test_frequency_hz"].get<double>() / pair["model_frequency_hz"].get<double>(), 1.0, 0.005)
        << pair.dump();
  }
}

}  // namespace
}  // namespace ema
