// End-to-end test of `ema quality`: FRF files with built-in defects written as UFF 58, the JSON
// verdicts and numbers read back.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "curvefit/synthetic.hpp"
#include "ema/formats/io.hpp"

namespace ema {
namespace {

namespace fs = std::filesystem;

int RunEmaQuality(const std::string& arguments, const fs::path& dir, std::string* out) {
  const std::string cmd = std::string("\"") + EMA_EXECUTABLE + "\" " + arguments + " >\"" + (dir / "out.txt").string() +
                          "\" 2>&1";
  const int status = std::system(cmd.c_str());
  std::ifstream in(dir / "out.txt");
  std::stringstream ss;
  ss << in.rdbuf();
  *out = ss.str();
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

TEST(QualityCli, VerdictsAndNumbersInJson) {
  const fs::path dir = fs::path(EMA_TEST_TMP_DIR) / "quality_cli";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const auto truth = curvefit::test::MakeTruth({40.0, 95.0, 160.0}, {0.01, 0.015, 0.02}, 4);
  FrfSet set = curvefit::test::MakeFrfSet(truth, {0, 2}, 200.0, 0.5, 0.0, 1);
  set.h[0].col(2) *= 1.1;   // H(3/1) 10 % off its reciprocal H(1/3)
  set.h[1].col(2) *= -1.0;  // driving point 3/3 inverted
  set.coherence.assign(2, Eigen::MatrixXd::Constant(set.LineCount(), 4, 0.99));
  set.averages = Eigen::MatrixXi::Constant(2, 4, 5);
  formats::WriteFrfSet(dir / "frf.unv", set);

  ModeSet modes;
  modes.dofs = {{1, 3}, {2, 3}};
  Mode m;
  m.frequency_hz = 40.0;
  m.damping_ratio = 0.01;
  m.shape = Eigen::VectorXcd(2);
  m.shape << 1.0, std::polar(1.0, 30.0 * M_PI / 180.0);  // MPC = cos^2 30° = 0.75, MCF 0.25, MPD 15°
  modes.modes.push_back(m);
  formats::WriteModeSet(dir / "modes.unv", modes);

  std::string out;
  ASSERT_EQ(RunEmaQuality("quality \"" + (dir / "frf.unv").string() + "\" --modes \"" + (dir / "modes.unv").string() +
                    "\" --json \"" + (dir / "q.json").string() + "\"",
                dir, &out),
            0)
      << out;
  EXPECT_NE(out.find("warn"), std::string::npos) << out;
  std::ifstream in(dir / "q.json");
  const auto j = nlohmann::json::parse(in);
  EXPECT_EQ(j["verdict"], "warn");
  ASSERT_EQ(j["reciprocity"].size(), 1u);
  // 0.1 / 1.05 by construction; the tolerance covers the digits UFF 58 stores.
  EXPECT_NEAR(j["reciprocity"][0]["relative_difference"].get<double>(), 0.1 / 1.05, 1e-6);
  EXPECT_EQ(j["reciprocity"][0]["verdict"], "warn");
  ASSERT_EQ(j["driving_points"].size(), 2u);
  EXPECT_EQ(j["driving_points"][0]["verdict"], "pass");
  EXPECT_EQ(j["driving_points"][1]["verdict"], "warn");
  EXPECT_EQ(j["driving_points"][1]["dof"]["node"], 3);
  EXPECT_EQ(j["driving_points"][1]["flipped"], 3);
  ASSERT_EQ(j["coherence_map"]["labels"].size(), 8u);
  EXPECT_EQ(j["coherence_map"]["coherence"][0].size(), j["coherence_map"]["frequency_hz"].size());
  EXPECT_EQ(j["frfs"][0]["averages"], 5);
  EXPECT_EQ(j["frfs"][0]["scatter_verdict"], "pass");
  ASSERT_EQ(j["modes"].size(), 1u);
  EXPECT_NEAR(j["modes"][0]["mpc"].get<double>(), 0.75, 1e-6);  // shape written with ~7 digits
  EXPECT_NEAR(j["modes"][0]["mcf"].get<double>(), 0.25, 1e-6);
  EXPECT_NEAR(j["modes"][0]["mpd_deg"].get<double>(), 15.0, 1e-4);
  EXPECT_EQ(j["modes"][0]["verdict"], "warn");

  // Bad usage and bad input exit 2 and 1.
  EXPECT_EQ(RunEmaQuality("quality", dir, &out), 2);
  EXPECT_EQ(RunEmaQuality("quality \"" + (dir / "frf.unv").string() + "\" --reciprocity-tol 0", dir, &out), 2);
  EXPECT_EQ(RunEmaQuality("quality \"" + (dir / "missing.unv").string() + "\"", dir, &out), 1);
  // The JSON may not replace an input (exit 2, the input untouched).
  const auto before = fs::file_size(dir / "modes.unv");
  EXPECT_EQ(RunEmaQuality("quality \"" + (dir / "frf.unv").string() + "\" --modes \"" + (dir / "modes.unv").string() +
                              "\" --json \"" + (dir / "modes.unv").string() + "\"",
                          dir, &out),
            2);
  EXPECT_EQ(fs::file_size(dir / "modes.unv"), before);
}

}  // namespace
}  // namespace ema

namespace ema {
namespace {

TEST(QualityCli, StabilisationJsonCarriesCmifAndMmif) {
  // Two close modes (100/102 Hz, 2 %) with orthogonal participation at the two references, as in
  // tests/curvefit/mode_indicators_test.cpp, through `ema fit --stabilisation`.
  const fs::path dir = fs::path(EMA_TEST_TMP_DIR) / "quality_cli_cmif";
  fs::remove_all(dir);
  fs::create_directories(dir);
  auto truth = curvefit::test::MakeTruth({40.0, 100.0, 102.0}, {0.01, 0.02, 0.02}, 6);
  truth.modes[1].shape << 0.5, 0.5, 0.25, 0.4, 0.15, 0.3;
  truth.modes[2].shape << 0.3, -0.3, 0.21, -0.12, 0.27, -0.06;
  formats::WriteFrfSet(dir / "frf.unv", curvefit::test::MakeFrfSet(truth, {0, 1}, 150.0, 0.1, 0.0, 1));
  std::string out;
  ASSERT_EQ(RunEmaQuality("fit \"" + (dir / "frf.unv").string() + "\" -o \"" + (dir / "m.unv").string() +
                              "\" --band 20:140 --order-max 20 --stabilisation \"" + (dir / "s.json").string() + "\"",
                          dir, &out),
            0)
      << out;
  std::ifstream in(dir / "s.json");
  const auto j = nlohmann::json::parse(in);
  const auto& f = j.at("cmif").at("frequency_hz");
  const auto& sv = j.at("cmif").at("values");
  ASSERT_EQ(sv.size(), 2u);  // min(6 outputs, 2 references) singular values
  ASSERT_EQ(sv[1].size(), f.size());
  ASSERT_EQ(j.at("mmif").at("values").size(), 2u);
  // Largest second singular value between 95 and 110 Hz: at the weaker close mode (102 Hz, the
  // peak line on a 0.1 Hz grid within 0.3 Hz).
  double best = -1.0, at = 0.0;
  for (size_t k = 0; k < f.size(); ++k) {
    const double hz = f[k].get<double>();
    if (hz < 95.0 || hz > 110.0 || sv[1][k].is_null()) continue;
    if (sv[1][k].get<double>() > best) best = sv[1][k].get<double>(), at = hz;
  }
  EXPECT_NEAR(at, 102.0, 0.3);
}

}  // namespace
}  // namespace ema
