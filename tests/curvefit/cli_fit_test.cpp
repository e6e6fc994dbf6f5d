// `ema fit` end to end on the measured beam sample (runs the built executable; skipped only when
// the executable has not been built, e.g. when just this test target was built).
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <cmath>
#include <fstream>
#include <map>
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
  EXPECT_EQ(RunEma("fit " + sample_ + " -o " + unv.string() + " --refine maybe"), 2);
  EXPECT_EQ(RunEma("fit " + sample_), 2);  // -o missing
}

// ---- One test per option (issue 17): each asserts the option's effect, so an ignored or
// mis-wired option fails. The beam in 30..300 Hz at orders up to 40 keeps each run well under 1 s.

class FitOptions : public FitCli {
 protected:
  /// Runs `ema fit` on the beam band with extra options; returns {MODES.json, STAB.json}.
  std::pair<nlohmann::json, nlohmann::json> Fit(const std::string& tag, const std::string& extra) {
    const fs::path m = dir_ / (tag + ".json"), s = dir_ / (tag + "-stab.json");
    EXPECT_EQ(RunEma("fit " + sample_ + " -o " + (dir_ / (tag + ".unv")).string() + " --json " + m.string() +
                     " --stabilisation " + s.string() + " --band 30:300 --order-max 40 " + extra),
              0)
        << extra;
    return {ReadJson(m), ReadJson(s)};
  }
  static std::map<std::string, int> Labels(const nlohmann::json& stab) {
    std::map<std::string, int> n;
    for (const auto& o : stab.at("orders"))
      for (const auto& p : o.at("poles")) ++n[p.at("label").get<std::string>()];
    return n;
  }
};

TEST_F(FitOptions, SelectGivesExactlyTheModesAskedFor) {
  const auto [all, stab_all] = Fit("all", "");
  ASSERT_EQ(all.at("modes").size(), 3u);
  const auto [two, stab_two] = Fit("two", "--select 51.5,278.7");
  ASSERT_EQ(two.at("modes").size(), 2u);
  // The selected poles are those of the diagram nearest the given frequencies: 51.52 and 278.67 Hz.
  EXPECT_NEAR(two["modes"][0]["frequency_hz"].get<double>(), 51.52, 0.02);
  EXPECT_NEAR(two["modes"][1]["frequency_hz"].get<double>(), 278.67, 0.02);
  // Two modes leave the 142 Hz resonance unexplained: the synthesis error must grow well above
  // the three-mode fit's (3 % on this band).
  EXPECT_LT(all.at("synthesis_error").get<double>(), 0.05);
  EXPECT_GT(two.at("synthesis_error").get<double>(), 3.0 * all.at("synthesis_error").get<double>());
}

TEST_F(FitOptions, ThreadsDoNotChangeTheModes) {
  const auto [one, s1] = Fit("t1", "--threads 1");
  const auto [two, s2] = Fit("t2", "--threads 2");
  EXPECT_EQ(one.at("modes"), two.at("modes"));
  EXPECT_EQ(s1.at("orders"), s2.at("orders"));
  EXPECT_EQ(RunEma("fit " + sample_ + " -o " + (dir_ / "x.unv").string() + " --threads -1"), 2);
}

TEST_F(FitOptions, StabilityTolerancesChangeTheLabels) {
  const auto [m0, base] = Fit("base", "");
  const auto n0 = Labels(base);
  EXPECT_EQ(base.at("criteria").at("frequency_tol"), 0.01);
  ASSERT_GT(n0.count("s") ? n0.at("s") : 0, 30) << "the beam's three modes are stable over most orders";
  // Nothing is within 1e-9 in frequency from one order to the next: no pole is stable at all, so
  // automatic selection finds no mode (exit 1); a mode asked for by frequency still comes out.
  EXPECT_EQ(RunEma("fit " + sample_ + " -o " + (dir_ / "none.unv").string() + " --band 30:300 --order-max 40 --freq-tol 1e-9"), 1);
  const auto [m1, tight_f] = Fit("f", "--freq-tol 1e-9 --select 51.5");
  const auto n1 = Labels(tight_f);
  EXPECT_DOUBLE_EQ(tight_f.at("criteria").at("frequency_tol").get<double>(), 1e-9);
  EXPECT_EQ(n1.count("s") + n1.count("d") + n1.count("v") + n1.count("f"), 0u);
  // A damping tolerance of 1e-9: the frequency-stable poles lose their 'd'/'s' label for 'f'/'v'.
  const auto [m2, tight_d] = Fit("d", "--damping-tol 1e-9 --select 51.5");
  const auto n2 = Labels(tight_d);
  EXPECT_EQ(n2.count("s") + n2.count("d"), 0u);
  EXPECT_EQ(n2.at("v"), n0.at("s") + (n0.count("v") ? n0.at("v") : 0)) << "every s pole becomes v";
  // MAC of 1 - 1e-12 between orders is out of reach: every 's' becomes 'd'.
  const auto [m3, tight_mac] = Fit("mac", "--mac-min 0.999999999999 --select 51.5");
  const auto n3 = Labels(tight_mac);
  EXPECT_EQ(n3.count("s"), 0u);
  EXPECT_EQ(n3.at("d"), n0.at("s") + (n0.count("d") ? n0.at("d") : 0));
  EXPECT_DOUBLE_EQ(tight_mac.at("criteria").at("mac_min").get<double>(), 0.999999999999);
}

TEST_F(FitOptions, MpcAndMpdMatchAHandComputationFromTheWrittenShapes) {
  // From the shape values the JSON carries (full double precision), with the 2×2 scatter matrix
  // S of [Re ψ, Im ψ] (eigenvalues λ1 ≥ λ2, principal direction v):
  //   MPC = ((λ1 − λ2) / (λ1 + λ2))²                         (Pappa; 1 = real mode)
  //   MPD = Σ|ψ| acos(|Re ψ vx + Im ψ vy| / |ψ|) / Σ|ψ|      (Reynders 2012; degrees here)
  const auto [m, s] = Fit("mpd", "");
  ASSERT_EQ(m.at("modes").size(), 3u);
  for (const auto& mode : m.at("modes")) {
    double sxx = 0, syy = 0, sxy = 0;
    std::vector<std::pair<double, double>> psi;
    for (const auto& v : mode.at("shape")) {
      psi.emplace_back(v["value"][0].get<double>(), v["value"][1].get<double>());
      sxx += psi.back().first * psi.back().first;
      syy += psi.back().second * psi.back().second;
      sxy += psi.back().first * psi.back().second;
    }
    const double mean = 0.5 * (sxx + syy), dev = std::sqrt(0.25 * (sxx - syy) * (sxx - syy) + sxy * sxy);
    const double l1 = mean + dev, l2 = mean - dev;
    EXPECT_NEAR(mode.at("mpc").get<double>(), std::pow((l1 - l2) / (l1 + l2), 2), 1e-9);
    // MCF = 1 - |psi^T psi|^2 / (psi^H psi)^2 = 4 l1 l2 / (l1 + l2)^2 (pyEMA: MCF).
    EXPECT_NEAR(mode.at("mcf").get<double>(), 4.0 * l1 * l2 / ((l1 + l2) * (l1 + l2)), 1e-9);
    const double angle = 0.5 * std::atan2(2.0 * sxy, sxx - syy);  // principal direction of S
    const double vx = std::cos(angle), vy = std::sin(angle);
    double num = 0, den = 0;
    for (const auto& [re, im] : psi) {
      const double mag = std::hypot(re, im);
      num += mag * std::acos(std::min(1.0, std::abs(re * vx + im * vy) / mag));
      den += mag;
    }
    EXPECT_NEAR(mode.at("mpd_deg").get<double>(), num / den * 180.0 / M_PI, 1e-6);
    // The beam's modes are nearly real (ζ < 0.1 %): MPD under 2°.
    EXPECT_LT(mode.at("mpd_deg").get<double>(), 2.0);
  }
}

TEST_F(FitCli, NarrowBandFindsTheModeOrExitsOneNeverZeroWithoutAMode) {
  // 26 lines around the 52 Hz mode: found (issue 14, narrow-band selection).
  const fs::path unv = dir_ / "narrow.unv", json = dir_ / "narrow.json";
  ASSERT_EQ(RunEma("fit " + sample_ + " -o " + unv.string() + " --band 40:65 --json " + json.string()), 0);
  std::ifstream in(json);
  const nlohmann::json j = nlohmann::json::parse(in);
  ASSERT_EQ(j.at("modes").size(), 1u);
  EXPECT_NEAR(j["modes"][0].at("frequency_hz").get<double>(), 52.0, 0.015 * 52.0);  // as the full-band test
  // A band between modes (90..100 Hz, 11 lines) holds none: exit 1 and nothing written, for
  // PolyMAX and for peak picking alike.
  const fs::path none = dir_ / "none.unv";
  EXPECT_EQ(RunEma("fit " + sample_ + " -o " + none.string() + " --band 90:100"), 1);
  EXPECT_EQ(RunEma("fit " + sample_ + " -o " + none.string() + " --band 90:100 --method peak"), 1);
  EXPECT_FALSE(fs::exists(none));
}

}  // namespace
