// Issue 14 acceptance, end to end with known truth: samples/joint (a block on a micro-slipping
// Iwan joint) hammered at four force levels and integrated in time, then
// ema frf --force-bins 4 -> ema fit per bin -> ema amplitude. The joint's mode softens and its
// damping rises; the rocking modes, which leave the joint at rest, stay linear; the same chain
// on the model with a linear joint says "none" everywhere. The fitted frequency drop is checked
// against the drop of the noise-free simulated response itself (energy-weighted frequency of
// its free decay, docs/amplitude.md).
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>

#include "ema/formats/io.hpp"
#include "test_files.hpp"

namespace ema {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

const fs::path kSample = fs::path(EMA_SOURCE_DIR) / "samples" / "joint";
// Exponential window, 1/s: a decay time of 5 ms (about one cycle of the 252 Hz mode), so each
// FRF measures the response near the impact's peak amplitude rather than an average over the
// whole ring-down, in which the joint sweeps from slipping to stuck and the fit splits the mode
// into two poles (docs/amplitude.md, limits). With it the fitted drop lands within 3 % of the
// truth's for seeds 3..7 (a weaker window of 120 1/s: within 20 %, 80 1/s: 44 % off).
constexpr int kWindowRate = 200;

using test::Slurp;

void Write(const fs::path& p, const std::string& text) { std::ofstream(p) << text; }

using test::RunEma;

json Load(const fs::path& p) {
  std::ifstream in(p);
  return json::parse(in);
}

// simulate -> frf (4 bins) -> fit per bin -> amplitude; returns the amplitude JSON.
json Chain(const fs::path& dir, const fs::path& model, const fs::path& plan) {
  const std::string d = dir.string() + "/";
  EXPECT_EQ(RunEma("simulate " + model.string() + " --plan " + plan.string() + " -o " + d + "time.unv", dir), 0)
      << Slurp(dir / "stderr.txt");
  EXPECT_EQ(RunEma("frf " + d + "time.unv -o " + d + "frf.unv --force-bins 4 --exp-window " + std::to_string(kWindowRate) + " --json " + d + "frf.json", dir), 0)
      << Slurp(dir / "stderr.txt");
  const json frf = Load(dir / "frf.json");
  EXPECT_EQ(frf["bins"].size(), 4u);
  std::string levels;
  for (const json& bin : frf["bins"]) {
    const std::string n = std::to_string(bin["bin"].get<int>());
    EXPECT_EQ(bin["file"].get<std::string>(), d + "frf.bin" + n + ".unv");
    EXPECT_EQ(bin["impacts"], 5);  // 5 impacts per level, levels far apart: one level per bin
    EXPECT_EQ(RunEma("fit " + bin["file"].get<std::string>() + " -o " + d + "modes" + n + ".unv", dir), 0)
        << Slurp(dir / "stderr.txt");
    std::ostringstream level;
    level.precision(10);
    level << bin["level"].get<double>();
    levels += " --level " + level.str() + "=" + d + "modes" + n + ".unv";
  }
  EXPECT_EQ(RunEma("amplitude" + levels + " --json " + d + "amp.json", dir), 0) << Slurp(dir / "stderr.txt");
  return Load(dir / "amp.json");
}

const json* ModeNear(const json& amp, double f_hz) {
  for (const json& m : amp["modes"])
    if (std::abs(m["levels"][0]["frequency_hz"].get<double>() - f_hz) < 0.02 * f_hz) return &m;
  return nullptr;
}

// Energy-weighted frequency of a free decay: cycles between upward zero crossings after the
// pulse, each weighted by its energy under the same exponential window the FRFs use (what a fit
// of the windowed FRF of a decay that sweeps the amplitude averages over, docs/amplitude.md).
double DecayFrequencyHz(const TimeRecord& r) {
  const std::vector<double>& y = r.samples;
  const double dt = r.sample_interval_s;
  const double t0 = 0.05;  // the pulse starts at the pre-trigger, 5 % of the 1 s record
  std::vector<double> crossings;
  for (size_t i = static_cast<size_t>((t0 + 0.002) / dt); i + 1 < y.size(); ++i)  // after the 1 ms pulse
    if (y[i] <= 0.0 && y[i + 1] > 0.0) crossings.push_back((i + y[i] / (y[i] - y[i + 1])) * dt);
  double sw = 0.0, sf = 0.0;
  for (size_t k = 0; k + 1 < crossings.size(); ++k) {
    double e = 0.0;
    for (size_t i = static_cast<size_t>(crossings[k] / dt); i < static_cast<size_t>(crossings[k + 1] / dt); ++i)
      e += y[i] * y[i] * std::exp(-2.0 * kWindowRate * (i * dt - t0));
    sw += e;
    sf += e / (crossings[k + 1] - crossings[k]);
  }
  return sf / sw;
}

TEST(AmplitudeChain, MicroSlipJointSoftensAndDampsMoreAndTheLinearJointDoesNot) {
  const fs::path dir = fs::path(EMA_TEST_TMP_DIR) / ("amplitude_chain_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir / "slip");
  fs::create_directories(dir / "linear");
  fs::create_directories(dir / "truth");
  const fs::path model = kSample / "model.toml", plan = kSample / "plan.toml";

  const json amp = Chain(dir / "slip", model, plan);
  EXPECT_EQ(amp["level_kind"], "peak_force");
  const json* joint = ModeNear(amp, 251.6);
  ASSERT_NE(joint, nullptr) << amp.dump(1);
  EXPECT_EQ((*joint)["frequency_trend"], "softening") << joint->dump(1);
  EXPECT_EQ((*joint)["damping_trend"], "rising") << joint->dump(1);
  EXPECT_EQ((*joint)["levels"].size(), 4u);
  for (double f : {301.6, 389.1}) {  // rocking modes: the joint is on their axes
    const json* m = ModeNear(amp, f);
    ASSERT_NE(m, nullptr) << f;
    EXPECT_EQ((*m)["frequency_trend"], "none") << m->dump(1);
    EXPECT_EQ((*m)["damping_trend"], "none") << m->dump(1);
  }

  // Truth: the same test without noise or force spread, one impact per level; the drop of the
  // decay frequency at sensor 1+Z (on both rocking axes: it sees the joint's mode alone).
  std::string truth_plan = Slurp(plan);
  truth_plan = std::regex_replace(truth_plan, std::regex("impacts = 5"), "impacts = 1");
  truth_plan = std::regex_replace(truth_plan, std::regex("force_spread = 0.1"), "force_spread = 0.0");
  truth_plan = std::regex_replace(truth_plan, std::regex("response_noise = 0.01"), "response_noise = 0.0");
  truth_plan = std::regex_replace(truth_plan, std::regex("force_noise = 0.002"), "force_noise = 0.0\ntrigger_jitter = false");
  Write(dir / "truth" / "plan.toml", truth_plan);
  ASSERT_EQ(RunEma("simulate " + model.string() + " --plan " + (dir / "truth" / "plan.toml").string() + " -o " +
                       (dir / "truth" / "time.unv").string(),
                   dir / "truth"),
            0)
      << Slurp(dir / "truth" / "stderr.txt");
  std::vector<double> decay_hz;
  for (const TimeRecord& r : formats::ReadTimeRecords(dir / "truth" / "time.unv"))
    if (r.quantity != Quantity::kForce && r.channel == Dof{1, 3}) decay_hz.push_back(DecayFrequencyHz(r));
  ASSERT_EQ(decay_hz.size(), 4u);  // impacts 1..4 = levels 2, 5, 12, 30 N
  const double truth_pct = 100.0 * (decay_hz.back() - decay_hz.front()) / decay_hz.front();
  const double fitted_pct = (*joint)["frequency_change_pct"].get<double>();
  RecordProperty("truth_drop_pct", std::to_string(truth_pct));
  RecordProperty("fitted_drop_pct", std::to_string(fitted_pct));
  EXPECT_LT(truth_pct, -0.3);  // the truth softens clearly
  // Acceptance (issue 14): the fitted drop within 20 % of the truth's.
  EXPECT_NEAR(fitted_pct, truth_pct, 0.2 * std::abs(truth_pct)) << "truth " << truth_pct << " %, fitted " << fitted_pct;

  // Linear reference: the joint as a linear spring of its stuck stiffness, same test.
  std::string linear = Slurp(model);
  linear = std::regex_replace(linear, std::regex("micro_slip = \\{ k = 1.0e6, slip_force = 6.0, elements = 50 \\}"),
                              "linear = { k = 1.0e6 }");
  ASSERT_NE(linear.find("linear = { k = 1.0e6 }"), std::string::npos);
  Write(dir / "linear" / "model.toml", linear);
  const json ref = Chain(dir / "linear", dir / "linear" / "model.toml", plan);
  ASSERT_EQ(ref["modes"].size(), 3u) << ref.dump(1);
  for (const json& m : ref["modes"]) {
    EXPECT_EQ(m["frequency_trend"], "none") << m.dump(1);
    EXPECT_EQ(m["damping_trend"], "none") << m.dump(1);
  }
}

TEST(AmplitudeChain, RealHammerImpactsOfALinearArticleSplitByForceStayNone) {
  // Real data (tests/data/real/hammer-pyfrf): five impacts of 69-89 N on one article, split into two
  // force bins, fitted and compared: a linear structure over a 1.15x force range, so every mode
  // must come out `none` (the floors are meant for exactly this repeatability).
  const fs::path data = fs::path(EMA_REAL_DATA_DIR) / "hammer-pyfrf" / "hammer-5-impacts.unv";
  if (!fs::exists(data)) FAIL() << "shared data not found: " << data;
  const fs::path dir = fs::path(EMA_TEST_TMP_DIR) / ("amplitude_real_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string d = dir.string() + "/";
  ASSERT_EQ(RunEma("frf " + data.string() + " -o " + d + "frf.unv --force-bins 2 --json " + d + "frf.json", dir), 0)
      << Slurp(dir / "stderr.txt");
  const json frf = Load(dir / "frf.json");
  ASSERT_EQ(frf["bins"].size(), 2u);
  EXPECT_EQ(frf["bins"][0]["impacts"].get<int>() + frf["bins"][1]["impacts"].get<int>(), 5);
  EXPECT_LT(frf["bins"][0]["peak_force_max_n"].get<double>(), frf["bins"][1]["peak_force_min_n"].get<double>());
  std::string levels;
  for (int b = 1; b <= 2; ++b) {
    const std::string n = std::to_string(b);
    ASSERT_EQ(RunEma("fit " + d + "frf.bin" + n + ".unv -o " + d + "m" + n + ".unv", dir), 0) << Slurp(dir / "stderr.txt");
    levels += " --level " + std::to_string(frf["bins"][b - 1]["level"].get<double>()) + "=" + d + "m" + n + ".unv";
  }
  ASSERT_EQ(RunEma("amplitude" + levels + " --json " + d + "amp.json", dir), 0) << Slurp(dir / "stderr.txt");
  const json amp = Load(dir / "amp.json");
  ASSERT_GE(amp["modes"].size(), 5u);  // 810, 900, 2640, 3669, 5969, 6077 Hz, ... found in both bins
  for (const json& m : amp["modes"]) {
    EXPECT_EQ(m["frequency_trend"], "none") << m.dump(1);
    EXPECT_EQ(m["damping_trend"], "none") << m.dump(1);
  }
}

}  // namespace
}  // namespace ema
