// `ema fit` end to end on the measured beam sample (runs the built executable; skipped only when
// the executable has not been built, e.g. when just this test target was built).
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

namespace {

namespace fs = std::filesystem;

int RunEma(const std::string& args) {
  const std::string cmd = std::string(EMA_EXECUTABLE) + " " + args + " > /dev/null 2>&1";
  const int status = std::system(cmd.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

class FitCli : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!fs::exists(EMA_EXECUTABLE)) GTEST_SKIP() << "ema not built";
    // One folder per test: ctest runs the tests of this fixture in parallel processes.
    dir_ = fs::path(EMA_TEST_TMP_DIR) / ("curvefit_cli_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  fs::path dir_;
  const std::string sample_ = std::string(EMA_SOURCE_DIR) + "/samples/meas-point";
};

TEST_F(FitCli, MeasuredBeamWritesEveryOutput) {
  const fs::path unv = dir_ / "modes.unv", json = dir_ / "modes.json", stab = dir_ / "stab.json", svg = dir_ / "stab.svg";
  ASSERT_EQ(RunEma("fit " + sample_ + " -o " + unv.string() + " --json " + json.string() + " --stabilisation " +
                   stab.string() + " --plot " + svg.string()),
            0);
  ASSERT_TRUE(fs::exists(unv) && fs::exists(svg));
  std::ifstream in(json);
  const nlohmann::json j = nlohmann::json::parse(in);
  // cli.md contract: modes[].frequency_hz, damping_ratio, mpc, shape[].node/dir/value[re,im].
  ASSERT_EQ(j.at("modes").size(), 6u);
  const double expected[] = {52.0, 142.0, 279.0, 460.0, 687.0, 959.0};
  for (size_t r = 0; r < 6; ++r) {
    const auto& m = j["modes"][r];
    EXPECT_NEAR(m.at("frequency_hz").get<double>(), expected[r], 0.015 * expected[r]);
    EXPECT_GT(m.at("damping_ratio").get<double>(), 0.0);
    EXPECT_GT(m.at("mpc").get<double>(), 0.9);
    ASSERT_EQ(m.at("shape").size(), 3u);
    EXPECT_EQ(m["shape"][0].at("dir").get<std::string>(), "+X");
    EXPECT_EQ(m["shape"][0].at("value").size(), 2u);
    // cli.md "Uncertainty": 1 sigma from the data's noise, small against the value (the beam's
    // FRFs are clean: sigma_f well below 0.1 % of f).
    ASSERT_TRUE(m.at("frequency_std_hz").is_number());
    ASSERT_TRUE(m.at("damping_ratio_std").is_number());
    EXPECT_GT(m["frequency_std_hz"].get<double>(), 0.0);
    EXPECT_LT(m["frequency_std_hz"].get<double>(), 1e-3 * expected[r]);
  }
  EXPECT_EQ(j.at("refinement").at("method"), "ml");
  EXPECT_EQ(j.at("modal_model").at("frfs").size(), 3u);  // 3 hammer points x 1 sensor
  std::ifstream sin(stab);
  const nlohmann::json s = nlohmann::json::parse(sin);
  EXPECT_EQ(s.at("orders").size(), 120u);  // default: 120 orders for one reference
  EXPECT_EQ(s.at("selected").size(), 6u);
}

TEST_F(FitCli, BadInputAndUsage) {
  const fs::path unv = dir_ / "bad.unv";
  EXPECT_EQ(RunEma("fit " + sample_ + " -o " + unv.string() + " --band 2000:3000"), 1);  // no lines in band
  EXPECT_EQ(RunEma("fit " + sample_ + " -o " + unv.string() + " --order-max 5000"), 1);  // too few lines
  EXPECT_FALSE(fs::exists(unv)) << "nothing may be written on failure";
  EXPECT_EQ(RunEma("fit " + sample_ + " -o " + unv.string() + " --band 10"), 2);
  EXPECT_EQ(RunEma("fit " + sample_ + " -o " + unv.string() + " --plot x.pdf"), 2);
  EXPECT_EQ(RunEma("fit " + sample_ + " -o " + unv.string() + " --method lscf"), 2);
  EXPECT_EQ(RunEma("fit " + sample_ + " -o " + unv.string() + " --refine maybe"), 2);
  EXPECT_EQ(RunEma("fit " + sample_), 2);  // -o missing
}

}  // namespace
