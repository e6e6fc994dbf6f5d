// `ema correlate` options end to end (issue 17): --tolerance matches renumbered test nodes by
// position, --interface-damping moves the "interface-dominated" remark. Mode sets are written as
// UFF 55 with geometry (15), as `ema fit` and `ema model` write them.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>
#include <string>

#include "ema/formats/io.hpp"

namespace ema {
namespace {

namespace fs = std::filesystem;

int RunEma(const std::string& args, const fs::path& log) {
  const std::string cmd = std::string("\"") + EMA_EXECUTABLE + "\" " + args + " > \"" + log.string() + "\" 2>&1";
  const int status = std::system(cmd.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

nlohmann::json ReadJson(const fs::path& p) {
  std::ifstream in(p);
  return nlohmann::json::parse(in);
}

class CorrelateCli : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!fs::exists(EMA_EXECUTABLE)) FAIL() << "ema executable not built: " << EMA_EXECUTABLE;
    dir_ = fs::path(EMA_TEST_TMP_DIR) / ("correlate_cli_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    // Model: nodes 1..4 on a line 0.1 m apart, +X +Y +Z, three modes with random real shapes.
    model_.source = "model";
    for (int node = 1; node <= 4; ++node) {
      model_.geometry.push_back({node, Eigen::Vector3d(0.1 * node, 0, 0)});
      for (int dir = 1; dir <= 3; ++dir) model_.dofs.push_back({node, dir});
    }
    std::mt19937 rng(3);
    std::normal_distribution<double> g;
    for (double f : {100.0, 150.0, 230.0}) {
      Mode m;
      m.frequency_hz = f;
      m.shape.resize(12);
      for (int i = 0; i < 12; ++i) m.shape(i) = g(rng);
      model_.modes.push_back(m);
    }
    // Test: the same shapes at nodes renumbered 101..104 and 2 mm off; ζ = 0.5 %, 2 %, 4 %.
    test_ = model_;
    test_.source = "test";
    test_.geometry.clear();
    for (Dof& d : test_.dofs) d.node += 100;
    for (int node = 1; node <= 4; ++node) test_.geometry.push_back({node + 100, Eigen::Vector3d(0.1 * node + 0.002, 0, 0)});
    const double zeta[] = {0.005, 0.02, 0.04};
    for (int k = 0; k < 3; ++k) {
      test_.modes[k].frequency_hz *= 0.98;
      test_.modes[k].damping_ratio = zeta[k];
    }
    formats::WriteModeSet(dir_ / "model.unv", model_);
    formats::WriteModeSet(dir_ / "test.unv", test_);
  }
  std::string P(const std::string& name) const { return "\"" + (dir_ / name).string() + "\""; }
  fs::path dir_;
  ModeSet model_, test_;
};

TEST_F(CorrelateCli, ToleranceMatchesRenumberedNodesByPosition) {
  // By node id the two sets share nothing: bad input. Within 5 mm every node matches (2 mm off):
  // the three modes pair one to one with MAC 1 (same shapes; ASCII UFF keeps 6 digits) and
  // agreement 98 % (f_test = 0.98 f_model). 1 mm is tighter than the offset: bad input again.
  EXPECT_EQ(RunEma("correlate " + P("test.unv") + " " + P("model.unv") + " --json " + P("a.json"), dir_ / "a.log"), 1);
  EXPECT_FALSE(fs::exists(dir_ / "a.json"));
  ASSERT_EQ(RunEma("correlate " + P("test.unv") + " " + P("model.unv") + " --tolerance 0.005 --json " + P("b.json"), dir_ / "b.log"), 0);
  const nlohmann::json b = ReadJson(dir_ / "b.json");
  ASSERT_EQ(b.at("pairs").size(), 3u);
  for (int k = 0; k < 3; ++k) {
    EXPECT_EQ(b["pairs"][k]["test_mode"], k + 1);
    EXPECT_EQ(b["pairs"][k]["model_mode"], k + 1);
    EXPECT_NEAR(b["pairs"][k]["mac"].get<double>(), 1.0, 1e-9);
    EXPECT_NEAR(b["pairs"][k]["agreement_pct"].get<double>(), 98.0, 1e-3);
  }
  EXPECT_EQ(RunEma("correlate " + P("test.unv") + " " + P("model.unv") + " --tolerance 0.001", dir_ / "c.log"), 1);
}

TEST_F(CorrelateCli, InterfaceDampingMovesTheRemark) {
  auto remarked = [&](const std::string& threshold) {
    EXPECT_EQ(RunEma("correlate " + P("test.unv") + " " + P("model.unv") + " --tolerance 0.005 --interface-damping " +
                         threshold + " --json " + P("r.json"),
                     dir_ / "r.log"),
              0);
    std::vector<bool> out;
    const nlohmann::json j = ReadJson(dir_ / "r.json");
    for (const auto& p : j.at("pairs"))
      out.push_back(p.at("remark").get<std::string>().find("interface-dominated") != std::string::npos);
    return out;
  };
  EXPECT_EQ(remarked("0.01"), (std::vector<bool>{false, true, true}));  // the default: ζ > 1 %
  EXPECT_EQ(remarked("0.03"), (std::vector<bool>{false, false, true}));
  EXPECT_EQ(remarked("0.001"), (std::vector<bool>{true, true, true}));
}

}  // namespace
}  // namespace ema
