// A solver that does not converge is its own error kind (ema::ConvergenceError, exit 3), not bad
// input (exit 1): `ema simulate` integrating the joint sample in time with its micro-slip joint a
// million times stiffer and no oversampling cannot converge within one sample step.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <string>

#include "test_files.hpp"

namespace {

namespace fs = std::filesystem;

using ema::test::Slurp;

TEST(ConvergenceExit, TimeIntegrationThatCannotConvergeExitsWithThree) {
  const fs::path dir = fs::path(EMA_TEST_TMP_DIR) / ("convergence_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const fs::path joint = fs::path(EMA_SOURCE_DIR) / "samples" / "joint";
  std::string model = Slurp(joint / "model.toml"), plan = Slurp(joint / "plan.toml");
  model = std::regex_replace(model, std::regex(R"(micro_slip = \{ k = 1\.0e6)"), "micro_slip = { k = 1.0e12");
  plan = std::regex_replace(plan, std::regex(R"(force_levels_n = \[[^\]]*\])"), "force_levels_n = [3000.0]\noversampling = 1");
  plan = std::regex_replace(plan, std::regex(R"(impacts = 5)"), "impacts = 1");
  ASSERT_NE(model.find("k = 1.0e12"), std::string::npos);
  ASSERT_NE(plan.find("oversampling = 1"), std::string::npos);
  std::ofstream(dir / "model.toml") << model;
  std::ofstream(dir / "plan.toml") << plan;
  const fs::path out = dir / "time.unv";
  const std::string command = std::string(EMA_EXECUTABLE) + " simulate '" + (dir / "model.toml").string() + "' --plan '" +
                              (dir / "plan.toml").string() + "' -o '" + out.string() + "' > /dev/null 2> '" +
                              (dir / "stderr.txt").string() + "'";
  const int status = std::system(command.c_str());
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 3);
  const std::string err = Slurp(dir / "stderr.txt");
  EXPECT_NE(err.find("did not converge"), std::string::npos) << err;
  EXPECT_NE(err.find("plan.toml"), std::string::npos) << err;  // names the file whose settings to change
  EXPECT_NE(err.find("oversampling"), std::string::npos) << err;  // and what to change
  EXPECT_FALSE(fs::exists(out));  // nothing half-written
}

}  // namespace
