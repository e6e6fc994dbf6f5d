// `ema amplitude` as a black box: constructed mode sets at four levels in UFF 55, the JSON of
// cli.md, and the exit codes for too few levels and for no pairing.
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "ema/formats/io.hpp"
#include "test_files.hpp"

namespace ema {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

fs::path Dir(const std::string& name) {
  const fs::path d = fs::path(EMA_TEST_TMP_DIR) / (name + "_" + std::to_string(::getpid()));
  fs::create_directories(d);
  return d;
}

using test::RunEma;

using test::Slurp;

// Two modes on three DOFs; mode 1 at f1, ζ1, mode 2 fixed at 250 Hz, 0.8 %.
fs::path WriteModes(const fs::path& dir, const std::string& name, double f1, double zeta1) {
  ModeSet set;
  set.dofs = {{1, 3}, {2, 3}, {3, 3}};
  const double shapes[2][3] = {{1.0, 0.7, 0.3}, {1.0, -0.2, -0.9}};
  const double f[2] = {f1, 250.0}, z[2] = {zeta1, 0.008};
  for (int r = 0; r < 2; ++r) {
    Mode m;
    m.frequency_hz = f[r];
    m.damping_ratio = z[r];
    m.pole = FrequencyAndDampingToPole(f[r], z[r]);
    m.shape = Eigen::VectorXcd(3);
    for (int i = 0; i < 3; ++i) m.shape[i] = shapes[r][i];
    set.modes.push_back(m);
  }
  const fs::path p = dir / name;
  formats::WriteModeSet(p, set);
  return p;
}

TEST(AmplitudeCli, FourLevelsGiveTheJsonOfTheContract) {
  const fs::path dir = Dir("amplitude_cli");
  const double levels[4] = {0.03, 0.1, 0.25, 0.49};
  const double df[4] = {0.0, -0.1, -0.25, -0.33};   // % of f
  const double zf[4] = {1.0, 1.3, 1.6, 1.9};        // ζ factor
  std::string args = "amplitude";
  for (int i = 0; i < 4; ++i) {
    const fs::path p = WriteModes(dir, "m" + std::to_string(i) + ".unv", 100.0 * (1 + df[i] / 100), 0.01 * zf[i]);
    args += " --level " + std::to_string(levels[i]) + "=" + p.string();
  }
  ASSERT_EQ(RunEma(args + " --json " + (dir / "amp.json").string() + " --report " + (dir / "amp.html").string(), dir), 0)
      << Slurp(dir / "stderr.txt");
  const std::string html = Slurp(dir / "amp.html");  // the page embeds the JSON it draws
  EXPECT_NE(html.find("\"frequency_trend\":\"softening\""), std::string::npos);
  std::ifstream in(dir / "amp.json");
  const json j = json::parse(in);
  EXPECT_EQ(j["level_kind"], "peak_force");
  ASSERT_EQ(j["modes"].size(), 2u);
  const json& m1 = j["modes"][0];
  EXPECT_EQ(m1["mode"], 1);
  ASSERT_EQ(m1["levels"].size(), 4u);
  for (const char* key : {"level", "frequency_hz", "damping_ratio", "frequency_std_hz", "damping_ratio_std"})
    EXPECT_TRUE(m1["levels"][0].contains(key)) << key;
  EXPECT_TRUE(m1["levels"][0]["frequency_std_hz"].is_null());  // UFF 55 alone carries no σ
  EXPECT_EQ(m1["frequency_trend"], "softening");
  EXPECT_EQ(m1["damping_trend"], "rising");
  // The UFF 55 writer keeps 12 significant digits: the change is exact to 1e-6 %.
  EXPECT_NEAR(m1["frequency_change_pct"].get<double>(), -0.33, 1e-6);
  EXPECT_NEAR(m1["damping_ratio_factor"].get<double>(), 1.9, 1e-9);
  EXPECT_EQ(m1["reading"], "micro-slip in a joint: f \u22120.33 %, \u03b6 \u00d71.9 from 0.03 to 0.49 N");
  EXPECT_EQ(j["modes"][1]["frequency_trend"], "none");
  EXPECT_EQ(j["modes"][1]["damping_trend"], "none");
  EXPECT_NE(Slurp(dir / "stdout.txt").find("softening"), std::string::npos);

  // A sidecar MODES.json (ema fit --json) supplies σ: at 0.2 % per point the 0.33 % fall is no
  // longer significant.
  for (int i = 0; i < 4; ++i) {
    json side = {{"modes", json::array()}};
    side["modes"].push_back({{"frequency_hz", 100.0 * (1 + df[i] / 100)}, {"frequency_std_hz", 0.2}, {"damping_ratio_std", 0.005}});
    side["modes"].push_back({{"frequency_hz", 250.0}, {"frequency_std_hz", 0.5}, {"damping_ratio_std", 0.004}});
    std::ofstream(dir / ("m" + std::to_string(i) + ".json")) << side.dump();
  }
  ASSERT_EQ(RunEma(args + " --level-kind response --json " + (dir / "amp2.json").string(), dir), 0);
  std::ifstream in2(dir / "amp2.json");
  const json j2 = json::parse(in2);
  EXPECT_EQ(j2["level_kind"], "response");
  EXPECT_DOUBLE_EQ(j2["modes"][0]["levels"][0]["frequency_std_hz"].get<double>(), 0.2);
  EXPECT_EQ(j2["modes"][0]["frequency_trend"], "none");
  EXPECT_EQ(j2["modes"][0]["damping_trend"], "none");
}

TEST(AmplitudeCli, OneLevelOrNoPairExitsOneAndBadUsageTwo) {
  const fs::path dir = Dir("amplitude_cli_bad");
  const fs::path a = WriteModes(dir, "a.unv", 100.0, 0.01);
  EXPECT_EQ(RunEma("amplitude --level 1=" + a.string(), dir), 1);
  EXPECT_TRUE(Slurp(dir / "stdout.txt").empty());
  EXPECT_NE(Slurp(dir / "stderr.txt").find("two levels"), std::string::npos);
  // Modes 30 % apart in frequency: nothing pairs.
  ModeSet far = formats::ReadModeSet(a);
  for (Mode& m : far.modes) m.frequency_hz *= 1.3, m.pole = FrequencyAndDampingToPole(m.frequency_hz, m.damping_ratio);
  formats::WriteModeSet(dir / "far.unv", far);
  EXPECT_EQ(RunEma("amplitude --level 1=" + a.string() + " --level 2=" + (dir / "far.unv").string(), dir), 1);
  EXPECT_NE(Slurp(dir / "stderr.txt").find("no mode pairs"), std::string::npos);
  EXPECT_EQ(RunEma("amplitude --level x=" + a.string() + " --level 2=" + a.string(), dir), 2);
  EXPECT_EQ(RunEma("amplitude --level 1=" + a.string() + " --level 2=" + a.string() + " --level-kind volts", dir), 2);
  EXPECT_EQ(RunEma("amplitude --level 1=" + a.string() + " --level 2=" + a.string() + " --json " + a.string(), dir), 2);
}

}  // namespace
}  // namespace ema
