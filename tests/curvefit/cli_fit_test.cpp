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
    if (!fs::exists(EMA_EXECUTABLE)) FAIL() << "ema executable not built: " << EMA_EXECUTABLE;
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
  }
  std::ifstream sin(stab);
  const nlohmann::json s = nlohmann::json::parse(sin);
  EXPECT_EQ(s.at("orders").size(), 120u);  // default: 120 orders for one reference
  EXPECT_EQ(s.at("selected").size(), 6u);
}

nlohmann::json ReadJson(const fs::path& p) {
  std::ifstream in(p);
  return nlohmann::json::parse(in);
}

TEST_F(FitCli, FrfTableFitsLikeTheIndexedFolder) {
  // The sample's three column files written as one FRF table (any DOF names; here the sample's
  // own): the fit must be the same to the last digit, since the numbers read are the same.
  const fs::path table = dir_ / "beam.csv";
  {
    std::ifstream c1(sample_ + "/meas_point_1.txt"), c2(sample_ + "/meas_point_2.txt"), c3(sample_ + "/meas_point_3.txt");
    std::ofstream out(table);
    out << "# quantity: acceleration\nfrequency_hz, 1+X/1+X, 1+X/2+X, 1+X/3+X\n";
    std::string a, b, c;
    for (int line = 0; std::getline(c1, a) && std::getline(c2, b) && std::getline(c3, c); ++line)
      out << line << ", " << a << ", " << b << ", " << c << "\n";
  }
  const std::string options = " --band 30:300 --order-max 40";
  ASSERT_EQ(RunEma("fit " + sample_ + " -o " + (dir_ / "a.unv").string() + " --json " + (dir_ / "a.json").string() + options), 0);
  ASSERT_EQ(RunEma("fit " + table.string() + " -o " + (dir_ / "b.unv").string() + " --json " + (dir_ / "b.json").string() + options), 0);
  const nlohmann::json a = ReadJson(dir_ / "a.json"), b = ReadJson(dir_ / "b.json");
  ASSERT_EQ(a.at("modes").size(), 3u);  // 52, 142 and 279 Hz in 30..300 Hz
  ASSERT_EQ(b.at("modes").size(), a.at("modes").size());
  for (size_t k = 0; k < a["modes"].size(); ++k) {
    EXPECT_EQ(b["modes"][k]["frequency_hz"], a["modes"][k]["frequency_hz"]);
    EXPECT_EQ(b["modes"][k]["shape"], a["modes"][k]["shape"]);
  }
}

TEST_F(FitCli, BadInputAndUsage) {
  const fs::path unv = dir_ / "bad.unv";
  EXPECT_EQ(RunEma("fit " + sample_ + " -o " + unv.string() + " --band 2000:3000"), 1);  // no lines in band
  EXPECT_EQ(RunEma("fit " + sample_ + " -o " + unv.string() + " --order-max 5000"), 1);  // too few lines
  EXPECT_FALSE(fs::exists(unv)) << "nothing may be written on failure";
  EXPECT_EQ(RunEma("fit " + sample_ + " -o " + unv.string() + " --band 10"), 2);
  EXPECT_EQ(RunEma("fit " + sample_ + " -o " + unv.string() + " --plot x.pdf"), 2);
  EXPECT_EQ(RunEma("fit " + sample_ + " -o " + unv.string() + " --method lscf"), 2);
  EXPECT_EQ(RunEma("fit " + sample_), 2);  // -o missing
}

}  // namespace
