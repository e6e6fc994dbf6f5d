// The bolted-frame sample (samples/bolted-frame, issue 27): part matrices from the real FE code
// CalculiX, a simulated roving-hammer test of the truth with joint J3 at 30 % of its stiffness,
// and `ema run` naming that joint at rank 1 with its factor.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

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
}

}  // namespace
}  // namespace ema
