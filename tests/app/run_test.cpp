// `ema run` end to end on the guideway sample (samples/guideway): the hidden mount compliance is
// found, the updated model agrees with the test, the report renders, and the sample is untouched.
#include <gtest/gtest.h>

#include <fcntl.h>
#include <sys/file.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

#include "browser_check.hpp"
#include "guideway_run.hpp"
#include "ema/core/error.hpp"
#include "test_files.hpp"

namespace ema {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

const fs::path kSample = fs::path(EMA_SOURCE_DIR) / "samples" / "guideway";

using test::HashTree;

using test::Slurp;

json Load(const fs::path& path) {
  std::ifstream in(path);
  EXPECT_TRUE(in.good()) << path;
  return in ? json::parse(in) : json();
}

int RunEmaLogged(const std::string& args, const fs::path& log) {
  const std::string command = std::string(EMA_EXECUTABLE) + " " + args + " > '" + log.string() + "' 2>&1";
  const int status = std::system(command.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

// The sample's run, shared with every test process (tests/guideway_run.hpp).
class GuidewayRun : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    test::SharedGuidewayRun run = test::GuidewayRunOnce();
    out_ = new fs::path(run.out);
    log_ = new fs::path(run.log);
    before_ = new std::map<std::string, std::uint64_t>(std::move(run.before));
    exit_code_ = run.exit_code;
  }
  static void TearDownTestSuite() {
    delete out_;  // the output stays for the other processes (~20 MB in the build's tmp folder)
    delete log_;
    delete before_;
  }
  static fs::path* out_;
  static fs::path* log_;
  static std::map<std::string, std::uint64_t>* before_;
  static int exit_code_;
};
fs::path* GuidewayRun::out_ = nullptr;
fs::path* GuidewayRun::log_ = nullptr;
std::map<std::string, std::uint64_t>* GuidewayRun::before_ = nullptr;
int GuidewayRun::exit_code_ = -1;

TEST_F(GuidewayRun, CompletesAndKeepsEveryIntermediateFile) {
  ASSERT_EQ(exit_code_, 0) << std::ifstream(*log_).rdbuf();
  for (const char* test : {"stud-5um", "stud-9um"})
    for (const char* file : {"frf.unv", "frf.json", "modes.unv", "modes.json", "stabilisation.json", "model-before.json",
                             "correlation-before.json", "correlation-before.md", "model-after.json",
                             "correlation-after.json", "correlation-after.md"})
      EXPECT_TRUE(fs::is_regular_file(*out_ / test / file)) << test << "/" << file;
  for (const char* file : {"diagnosis.json", "updated-model.toml", "report.html", "summary.txt"})
    EXPECT_TRUE(fs::is_regular_file(*out_ / file)) << file;
}

TEST_F(GuidewayRun, PrintsNoWarningTheUserCannotActOn) {
  // The fit merges the pole the two roving sets see at slightly different frequencies (each
  // set's sensors load the carriage): handled, so a note in modes.json and the report, and no
  // `warning:` line on the terminal (a warning nobody can act on teaches users to skip warnings).
  ASSERT_EQ(exit_code_, 0);
  std::ifstream log(*log_);
  std::string line;
  while (std::getline(log, line)) EXPECT_EQ(line.find("warning:"), std::string::npos) << line;
  std::ifstream modes(*out_ / "stud-5um" / "modes.json");
  const std::string json((std::istreambuf_iterator<char>(modes)), {});
  EXPECT_NE(json.find("\"dropped\""), std::string::npos) << "the merged pole is still recorded";
}

TEST_F(GuidewayRun, NoReportWritesTheSameResultsWithoutThePage) {
  ASSERT_EQ(exit_code_, 0);
  const fs::path out = fs::path(EMA_TEST_TMP_DIR) / ("guideway-no-report-" + std::to_string(getpid()));
  fs::remove_all(out);
  ASSERT_EQ(RunEmaLogged("run '" + (kSample / "project.toml").string() + "' -o '" + out.string() + "' --no-report", out.string() + ".log"), 0);
  EXPECT_FALSE(fs::exists(out / "report.html"));
  EXPECT_TRUE(fs::is_regular_file(out / "summary.txt"));
  // The page is the only difference: the diagnosis is the same to the last digit.
  EXPECT_EQ(Load(out / "diagnosis.json"), Load(*out_ / "diagnosis.json"));
  fs::remove_all(out);
}

TEST_F(GuidewayRun, RanksTheMountComplianceFirst) {
  ASSERT_EQ(exit_code_, 0);
  const json diagnosis = Load(*out_ / "diagnosis.json");
  ASSERT_FALSE(diagnosis["candidates"].empty());
  const json& best = diagnosis["candidates"][0];
  EXPECT_EQ(best["rank"], 1);
  // The project declares the test's 11.2 g roving accelerometers (sensor_mass): they load each
  // set's points while it is measured and are no finding. Rank 1 is the mount compliance alone.
  ASSERT_EQ(best["effects"].size(), 1u) << diagnosis["explanation"];
  EXPECT_EQ(best["effects"][0]["kind"], "series_compliance");
  EXPECT_EQ(best["effects"][0]["target"], "bearings");
  EXPECT_GE(best["probability"].get<double>(), 0.9) << diagnosis["explanation"];
  for (const auto& e : diagnosis["effect_probabilities"]) EXPECT_NE(e["kind"], "added_mass") << e.dump();
  // The truth (truth/model.toml) is the air film in series with a Hertz ball joint at each pad
  // (E' = 58 GPa, R' = 8.29 mm). Fitted as a Hertz element with R' fixed at 1 mm, only E'·sqrt(R')
  // is identifiable: E' = 58e9·sqrt(8.29); the chain reaches it to 0.2 %, 1 % is asserted.
  const std::string law = best["effects"][0]["law"];
  ASSERT_NE(law.find("hertz"), std::string::npos) << law;
  EXPECT_NEAR(best["parameters"]["modulus"].get<double>() / (58e9 * std::sqrt(8.29)), 1.0, 0.01) << best.dump();
  // The first screen tells the story: the effect, its value with σ, the thesis's K_e per pad
  // (2.8 and 1.7 N/µm, Tables 7.1, 7.2 and 8.1), the adequacy to the test's noise.
  const std::string summary = Slurp(*out_ / "summary.txt");
  EXPECT_NE(summary.find("Diagnosis: the model misses 1 effect"), std::string::npos) << summary;
  EXPECT_NE(summary.find("Hertz contact E' = 16"), std::string::npos) << summary;
  EXPECT_NE(summary.find("per spring of 'bearings' now: 2.8 N/µm at stud-5um, 1.72 N/µm at stud-9um"), std::string::npos)
      << summary;
  EXPECT_NE(summary.find("Adequate to the test's noise: yes"), std::string::npos) << summary;
  EXPECT_EQ(summary.find("added_mass"), std::string::npos) << summary;
  // The agreement columns (99.1 % updated) beside the diagnosis's 0.0004 % error: the first
  // compares the model without the test's 11.2 g sensors, and the screen says so.
  EXPECT_NE(summary.find("without the test's own sensors (11.2 g per measured node)"), std::string::npos) << summary;
  EXPECT_TRUE(best["noise_consistent"].get<bool>());
}

TEST_F(GuidewayRun, UpdatedModelAgreesWithBothSetups) {
  ASSERT_EQ(exit_code_, 0);
  for (const char* test : {"stud-5um", "stud-9um"}) {
    const json before = Load(*out_ / test / "correlation-before.json");
    const json after = Load(*out_ / test / "correlation-after.json");
    // Before: the air film read at the stud setting is ~3x too stiff at 5 um (thesis Table 8.1,
    // scheme A 23 N/um against 2.8 N/um), so the agreement is far below 90 %.
    EXPECT_LT(before["summary"]["mean_agreement_pct"].get<double>(), 90.0) << test;
    // After: the acceptance figure (issue 26: ≥ 99 % in both setups; the updated model is
    // correlated bare, without the test's sensors, which cost it 0.9 %).
    EXPECT_GE(after["summary"]["mean_agreement_pct"].get<double>(), 99.0) << test;
    // All five rigid-body modes of the carriage are paired with the updated model.
    EXPECT_GE(after["pairs"].size(), 5u) << test;
  }
}

TEST_F(GuidewayRun, StepOutputsMatchTheSubcommand) {
  ASSERT_EQ(exit_code_, 0);
  // `ema run` calls the subcommands in-process: the same command typed by hand writes the same file.
  const fs::path modes = *out_ / "stud-9um" / "modes.unv", again = *out_ / "correlation-again.json";
  ASSERT_EQ(RunEmaLogged("correlate '" + modes.string() + "' '" + (kSample / "model.toml").string() +
                       "' --setup stud-9um --json '" + again.string() + "'",
                   *out_ / "correlate-again.log"),
            0);
  EXPECT_EQ(Load(again), Load(*out_ / "stud-9um" / "correlation-before.json"));
}

TEST_F(GuidewayRun, LeavesTheSampleUnchanged) {
  EXPECT_EQ(HashTree(kSample), *before_);
}

TEST_F(GuidewayRun, ReportRendersInHeadlessChromium) {
  ASSERT_EQ(exit_code_, 0);
  if (!test::ChromiumAvailable()) {
    if (!test::BrowserCheckMayBeSkipped()) FAIL() << "chromium missing in CI (scripts/install-deps.sh --test installs it)";
    GTEST_SKIP() << "chromium not installed (scripts/install-deps.sh --test)";
  }
  const test::BrowserResult r = test::CheckInChromium(*out_ / "report.html", *out_ / "browser");
  ASSERT_TRUE(r.ran);
  EXPECT_EQ(r.page_errors, "");
  EXPECT_EQ(r.console_errors, "");
  // Per test: coherence map, stabilisation, FRFs, 2 MAC matrices, mode shapes; then the ranking
  // and the error fall; then the diagnosed places on the geometry, the error per added effect
  // (rank 1 holds two effects here) and the history over runs.
  EXPECT_EQ(r.expected, 2 * 6 + 2 + 3);
  EXPECT_EQ(r.rendered, r.expected);
  EXPECT_EQ(r.rendered_divs, r.expected);
}

TEST(RunProjectFile, BadProjectExitsOneAndWritesNothing) {
  // The reader's messages: tests/formats/project_file_test.cpp. Through the CLI: exit 1 for bad
  // input, 2 for bad usage, and nothing written.
  const fs::path dir = fs::path(EMA_TEST_TMP_DIR) / "project-bad-cli";
  fs::create_directories(dir);
  std::ofstream(dir / "model.toml") << "[model]\nname = \"x\"\n";
  std::ofstream(dir / "unknown.toml") << "[project]\nmodel = \"model.toml\"\ncolour = 3\n";
  EXPECT_EQ(RunEmaLogged("run '" + (dir / "unknown.toml").string() + "' -o '" + (dir / "out").string() + "'", dir / "log1.txt"), 1);
  EXPECT_FALSE(fs::exists(dir / "out"));
  EXPECT_EQ(RunEmaLogged("run --no-such-option", dir / "log2.txt"), 2);
}

TEST(RunProjectFile, OutputBinaryWritesTheFrfsAs58b) {
  // [output] binary = true (docs/project-file.md): the FRF files are UFF 58b, the fit reads what
  // they hold, and the run still finds the five rigid-body modes of each setup.
  const fs::path dir = fs::path(EMA_TEST_TMP_DIR) / ("project-binary-" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::ifstream in(kSample / "project.toml");
  std::string text{std::istreambuf_iterator<char>(in), {}};
  for (const std::string name : {"model.toml", "data/stud-5um.unv", "data/stud-9um.unv"}) {
    // Built by append: GCC 12 warns (-Wrestrict, a false positive) on "literal" + std::string.
    std::string quoted(1, '"'), absolute(1, '"');
    quoted.append(name).append(1, '"');
    absolute.append((kSample / name).string()).append(1, '"');
    text.replace(text.find(quoted), quoted.size(), absolute);
  }
  std::ofstream(dir / "project.toml") << text << "\n[output]\nbinary = true\n";
  const fs::path out = dir / "out";
  ASSERT_EQ(RunEmaLogged("run '" + (dir / "project.toml").string() + "' -o '" + out.string() + "' --no-report", dir / "log.txt"), 0);
  for (const char* test : {"stud-5um", "stud-9um"}) {
    std::ifstream frf(out / test / "frf.unv", std::ios::binary);
    std::string line;
    std::getline(frf, line);  // "    -1"
    std::getline(frf, line);  // the dataset id: "    58b" + sizes for a binary 58
    EXPECT_EQ(line.substr(0, 7), "    58b") << test;
    EXPECT_EQ(Load(out / test / "modes.json")["modes"].size(), 5u) << test;
  }
  std::ifstream log(out / "logs" / "stud-5um-frf.txt");
  std::string first;
  std::getline(log, first);
  EXPECT_NE(first.find("--binary"), std::string::npos) << first;  // the equivalent command line says so
  fs::remove_all(dir);
}

}  // namespace
}  // namespace ema
