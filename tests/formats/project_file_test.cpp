// The project file of `ema run` (formats::ReadProjectFile, docs/project-file.md): bad input is an
// InputError naming the file, the line and the key or file at fault.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <utility>
#include <vector>

#include "ema/core/error.hpp"
#include "ema/curvefit/fit.hpp"
#include "ema/diagnose/diagnose.hpp"
#include "ema/formats/project_file.hpp"
#include "ema/frf/hammer_frf.hpp"

namespace ema::formats {
namespace {

namespace fs = std::filesystem;

TEST(ProjectFile, BadInputNamesFileLineAndKey) {
  const fs::path dir = fs::path(EMA_TEST_TMP_DIR) / "project-bad";
  fs::create_directories(dir);
  auto write = [&](const std::string& name, const std::string& text) {
    std::ofstream(dir / name) << text;
    return dir / name;
  };
  write("model.toml", "[model]\nname = \"x\"\n");
  const fs::path unknown = write("unknown.toml", "[project]\nmodel = \"model.toml\"\ncolour = 3\n");
  try {
    ReadProjectFile(unknown);
    FAIL() << "unknown key accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("unknown.toml:3"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("colour"), std::string::npos) << e.what();
  }
  const fs::path missing = write("missing.toml", "[project]\nmodel = \"model.toml\"\n[[test]]\ntime = [\"nope.unv\"]\n");
  try {
    ReadProjectFile(missing);
    FAIL() << "missing data file accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("nope.unv"), std::string::npos) << e.what();
  }
  EXPECT_THROW(ReadProjectFile(write("notests.toml", "[project]\nmodel = \"model.toml\"\n")), InputError);
}

TEST(ProjectFile, ReadsTheGuidewaySample) {
  const Project p = ReadProjectFile(fs::path(EMA_SOURCE_DIR) / "samples" / "guideway" / "project.toml");
  ASSERT_EQ(p.tests.size(), 2u);
  EXPECT_EQ(p.tests[0].name, "stud-5um");
  EXPECT_EQ(p.tests[0].setup, "stud-5um");
  ASSERT_EQ(p.tests[0].time.size(), 1u);
  EXPECT_TRUE(p.tests[0].time[0].is_absolute());  // resolved against the project's folder
  EXPECT_EQ(p.estimator, "H1");
  ASSERT_TRUE(p.band_hz.has_value());
  EXPECT_EQ(p.band_hz->first, 100.0);
  EXPECT_EQ(p.band_hz->second, 450.0);
  EXPECT_EQ(p.select, "auto");
  EXPECT_EQ(p.lines.size(), 20u);
  EXPECT_FALSE(p.binary);
  EXPECT_EQ(p.tests[0].select, "");  // [fit] select applies
  EXPECT_FALSE(p.tests[0].select_hz.has_value());
  EXPECT_FALSE(p.tests[0].pick);
  EXPECT_EQ(p.frf.estimator, frf::Estimator::kH1);
  EXPECT_EQ(p.fit.data.band_lo_hz, 100.0);
  EXPECT_EQ(p.fit.data.band_hi_hz, 450.0);
  EXPECT_TRUE(p.fit.select_frequencies_hz.empty());
  EXPECT_TRUE(p.select_hz.empty());
  EXPECT_EQ(p.fit_keys, (std::vector<std::string>{"band", "select"}));
}

// A test's own selection (a pick repeated without the browser) and pick = true (docs/pick.md):
// read as given; a selection `ema fit --select` would refuse is refused here, at its line.
TEST(ProjectFile, PerTestSelectAndPick) {
  const fs::path dir = fs::path(EMA_TEST_TMP_DIR) / "project-select";
  fs::create_directories(dir);
  std::ofstream(dir / "model.toml") << "[model]\nname = \"x\"\n";
  std::ofstream(dir / "frf.unv") << "";
  auto project = [&](const std::string& name, const std::string& test_keys) {
    std::ofstream(dir / name) << "[project]\nmodel = \"model.toml\"\n[[test]]\nfrf = \"frf.unv\"\n" << test_keys
                              << "[[test]]\nname = \"second\"\nfrf = \"frf.unv\"\n[fit]\nselect = \"auto\"\n";
    return dir / name;
  };
  const Project p = ReadProjectFile(project("good.toml", "select = \"196.4,267.25\"\npick = true\n"));
  ASSERT_EQ(p.tests.size(), 2u);
  EXPECT_EQ(p.tests[0].select, "196.4,267.25");
  ASSERT_TRUE(p.tests[0].select_hz.has_value());
  EXPECT_EQ(*p.tests[0].select_hz, (std::vector<double>{196.4, 267.25}));
  EXPECT_TRUE(p.tests[0].pick);
  EXPECT_EQ(p.tests[1].select, "");
  EXPECT_FALSE(p.tests[1].select_hz.has_value());  // [fit] select applies
  EXPECT_FALSE(p.tests[1].pick);
  for (const auto& [keys, what] : std::vector<std::pair<std::string, std::string>>{
           {"select = \"196.4,,267\"\n", "select"},
           {"select = \"196.4 Hz\"\n", "select"},
           {"select = \"-3\"\n", "select"},
           {"select = 196.4\n", "select"},
           {"pick = \"yes\"\n", "pick"}}) {
    try {
      ReadProjectFile(project("bad.toml", keys));
      ADD_FAILURE() << keys << " accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("bad.toml:5"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("'" + what + "'"), std::string::npos) << e.what();
    }
  }
}

// ---- The typed options of [frf], [fit] and [diagnose] (issue 38) ------------------------------

// A project with one test (FRFs given) and `tables` after it: [[test]] ends on line 4, so the
// first line of `tables` is line 5. Each test has its own folder: ctest runs the tests of this
// file in parallel processes, and two writing the same bad.toml read each other's file.
fs::path OptionsProject(const std::string& name, const std::string& tables) {
  const fs::path dir = fs::path(EMA_TEST_TMP_DIR) / "project-options" /
                       ::testing::UnitTest::GetInstance()->current_test_info()->name();
  fs::create_directories(dir);
  std::ofstream(dir / "model.toml") << "[model]\nname = \"x\"\n";
  std::ofstream(dir / "frf.unv") << "";
  std::ofstream(dir / name) << "[project]\nmodel = \"model.toml\"\n[[test]]\nfrf = \"frf.unv\"\n" << tables;
  return dir / name;
}

// The message of the InputError ReadProjectFile throws ("" when it reads the file).
std::string ReadError(const fs::path& path) {
  try {
    ReadProjectFile(path);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

// Every mapped field of the three options structs as a default-constructed struct holds it.
void ExpectDefaultOptions(const Project& p) {
  const frf::FrfOptions frf_default;
  const acquisition::ImpactOptions& impact = frf_default.impact;
  EXPECT_EQ(p.frf.estimator, frf_default.estimator);
  EXPECT_EQ(p.estimator, "H1");
  EXPECT_EQ(p.frf.band_lo_hz, frf_default.band_lo_hz);
  EXPECT_EQ(p.frf.band_hi_hz, frf_default.band_hi_hz);
  EXPECT_EQ(p.frf.impact.exp_window, impact.exp_window);
  EXPECT_EQ(p.frf.impact.exp_decay_rate, impact.exp_decay_rate);
  EXPECT_EQ(p.frf.impact.exp_end_level, impact.exp_end_level);
  EXPECT_EQ(p.frf.output_quantity, frf_default.output_quantity);
  EXPECT_EQ(p.frf.impact.trigger_level, impact.trigger_level);
  EXPECT_EQ(p.frf.impact.force_window_pulses, impact.force_window_pulses);
  EXPECT_EQ(p.frf.impact.double_hit_high, impact.double_hit_high);
  EXPECT_EQ(p.frf.impact.double_hit_low, impact.double_hit_low);
  EXPECT_EQ(p.frf.impact.double_hit_autocorrelation, impact.double_hit_autocorrelation);
  EXPECT_EQ(p.frf.impact.reject_double_hits, impact.reject_double_hits);
  EXPECT_EQ(p.frf.impact.overload_fraction, impact.overload_fraction);
  EXPECT_EQ(p.frf.impact.level_tolerance, impact.level_tolerance);
  EXPECT_EQ(p.frf.threads, frf_default.threads);

  const curvefit::FitOptions fit_default;
  EXPECT_EQ(p.fit.data.band_lo_hz, fit_default.data.band_lo_hz);
  EXPECT_EQ(p.fit.data.band_hi_hz, fit_default.data.band_hi_hz);
  EXPECT_EQ(p.fit.polymax.order_max, fit_default.polymax.order_max);
  EXPECT_EQ(p.fit.select_frequencies_hz, fit_default.select_frequencies_hz);
  EXPECT_EQ(p.fit.method, fit_default.method);
  EXPECT_EQ(p.fit.refine, fit_default.refine);
  EXPECT_EQ(p.fit.stability.frequency_tol, fit_default.stability.frequency_tol);
  EXPECT_EQ(p.fit.stability.damping_tol, fit_default.stability.damping_tol);
  EXPECT_EQ(p.fit.stability.mac_min, fit_default.stability.mac_min);
  EXPECT_EQ(p.fit.polymax.threads, fit_default.polymax.threads);
  EXPECT_FALSE(p.band_hz.has_value());
  EXPECT_FALSE(p.order_max.has_value());
  EXPECT_EQ(p.select, "auto");
  EXPECT_TRUE(p.select_hz.empty());

  const diagnose::DiagnoseOptions diagnose_default;
  EXPECT_EQ(p.diagnose.criterion, diagnose_default.criterion);
  EXPECT_EQ(p.diagnose.max_effects, diagnose_default.max_effects);
  EXPECT_EQ(p.diagnose.members, diagnose_default.members);
  EXPECT_EQ(p.diagnose.frequency_floor, diagnose_default.frequency_floor);
  EXPECT_EQ(p.diagnose.shape_sigma, diagnose_default.shape_sigma);
  EXPECT_EQ(p.diagnose.model_error, diagnose_default.model_error);
  EXPECT_EQ(p.diagnose.effect_prior_odds, diagnose_default.effect_prior_odds);
  EXPECT_EQ(p.diagnose.pairing.mac_min, diagnose_default.pairing.mac_min);
}

// Without the keys (no tables, or empty ones) the structs are exactly their defaults.
TEST(ProjectFile, OptionsWithoutKeysAreTheStructDefaults) {
  for (const std::string& tables : {std::string(), std::string("[frf]\n[fit]\n[diagnose]\n")}) {
    const Project p = ReadProjectFile(OptionsProject("defaults.toml", tables));
    ExpectDefaultOptions(p);
    EXPECT_TRUE(p.frf_keys.empty());
    EXPECT_TRUE(p.fit_keys.empty());
    EXPECT_TRUE(p.diagnose_keys.empty());
    EXPECT_TRUE(p.fit_extra.empty());
    EXPECT_TRUE(p.diagnose_extra.empty());
  }
}

// docs/project-file.md shows the [frf], [fit] and [diagnose] keys with their defaults: read as
// written there, they give the defaults.
TEST(ProjectFile, TheDocumentedDefaultsAreTheDefaults) {
  std::ifstream in(fs::path(EMA_SOURCE_DIR) / "docs" / "project-file.md");
  const std::string doc((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::size_t begin = doc.find("\n[frf]"), end = doc.find("\n[report]");
  ASSERT_NE(begin, std::string::npos);
  ASSERT_NE(end, std::string::npos);
  const Project p = ReadProjectFile(OptionsProject("documented.toml", doc.substr(begin + 1, end - begin)));
  ExpectDefaultOptions(p);
  EXPECT_GE(p.frf_keys.size(), 10u);  // the keys are there, not commented out
  EXPECT_GE(p.fit_keys.size(), 6u);
  EXPECT_EQ(p.diagnose_keys.size(), 11u);
}

// Every key into its field, each value other than the default.
TEST(ProjectFile, OptionKeysAreReadIntoTheirFields) {
  const Project p = ReadProjectFile(OptionsProject("keys.toml",
      "[frf]\n"
      "estimator = \"hv\"\n"                 // case-insensitive, as --estimator
      "band = [5, 800.5]\n"
      "exp_window = 12.5\n"
      "exp_end_level = 0.02\n"
      "quantity = \"mobility\"\n"
      "trigger_level = 0.2\n"
      "force_window = 4.0\n"
      "double_hit_ratio = 0.02\n"
      "double_hit_autocorrelation = 0.1\n"
      "accept_double_hits = true\n"
      "overload_fraction = 0.9\n"
      "level_tolerance = 0.25\n"
      "threads = 2\n"
      "[fit]\n"
      "band = [100.0, 600.0]\n"
      "order_max = 40\n"
      "select = \"196.4, 267.25\"\n"
      "method = \"peak\"\n"
      "refine = \"none\"\n"
      "freq_tol = 0.02\n"
      "damping_tol = 0.1\n"
      "mac_min = 0.9\n"
      "threads = 3\n"
      "[diagnose]\n"
      "criterion = \"bic\"\n"
      "max_effects = 2\n"
      "members = false\n"
      "frequency_floor = 2e-3\n"
      "shape_sigma = 0.02\n"
      "exact_form = true\n"
      "effect_prior_odds = 0.5\n"
      "mac_min = 0.7\n"));
  EXPECT_EQ(p.frf.estimator, frf::Estimator::kHv);
  EXPECT_EQ(p.estimator, "Hv");
  EXPECT_EQ(p.frf.band_lo_hz, 5.0);
  EXPECT_EQ(p.frf.band_hi_hz, 800.5);
  EXPECT_EQ(p.frf.impact.exp_window, acquisition::ExpWindowMode::kFixed);
  EXPECT_EQ(p.frf.impact.exp_decay_rate, 12.5);
  EXPECT_EQ(p.frf.impact.exp_end_level, 0.02);
  EXPECT_EQ(p.frf.output_quantity, Quantity::kVelocity);
  EXPECT_EQ(p.frf.impact.trigger_level, 0.2);
  EXPECT_EQ(p.frf.impact.force_window_pulses, 4.0);
  EXPECT_EQ(p.frf.impact.double_hit_high, 0.02);
  EXPECT_EQ(p.frf.impact.double_hit_low, 0.01);  // re-arms below half the ratio, as --double-hit-ratio
  EXPECT_EQ(p.frf.impact.double_hit_autocorrelation, 0.1);
  EXPECT_FALSE(p.frf.impact.reject_double_hits);
  EXPECT_EQ(p.frf.impact.overload_fraction, 0.9);
  EXPECT_EQ(p.frf.impact.level_tolerance, 0.25);
  EXPECT_EQ(p.frf.threads, 2);
  EXPECT_EQ(p.frf_keys.size(), 13u);

  EXPECT_EQ(p.fit.data.band_lo_hz, 100.0);
  EXPECT_EQ(p.fit.data.band_hi_hz, 600.0);
  ASSERT_TRUE(p.band_hz.has_value());
  EXPECT_EQ(*p.band_hz, std::make_pair(100.0, 600.0));
  EXPECT_EQ(p.fit.polymax.order_max, 40);
  EXPECT_EQ(p.order_max.value_or(0), 40);
  EXPECT_EQ(p.select, "196.4, 267.25");
  EXPECT_EQ(p.select_hz, (std::vector<double>{196.4, 267.25}));
  EXPECT_EQ(p.fit.select_frequencies_hz, p.select_hz);
  EXPECT_EQ(p.fit.method, curvefit::FitMethod::kPeak);
  EXPECT_EQ(p.fit.refine, curvefit::RefineMethod::kNone);
  EXPECT_EQ(p.fit.stability.frequency_tol, 0.02);
  EXPECT_EQ(p.fit.stability.damping_tol, 0.1);
  EXPECT_EQ(p.fit.stability.mac_min, 0.9);
  EXPECT_EQ(p.fit.polymax.threads, 3);
  EXPECT_EQ(p.fit_keys, (std::vector<std::string>{"band", "order_max", "select", "method", "refine", "freq_tol",
                                                  "damping_tol", "mac_min", "threads"}));

  EXPECT_EQ(p.diagnose.criterion, diagnose::Criterion::kBic);
  EXPECT_EQ(p.diagnose.max_effects, 2);
  EXPECT_FALSE(p.diagnose.members);
  EXPECT_EQ(p.diagnose.frequency_floor, 2e-3);
  EXPECT_EQ(p.diagnose.shape_sigma, 0.02);
  EXPECT_FALSE(p.diagnose.model_error);
  EXPECT_EQ(p.diagnose.effect_prior_odds, 0.5);
  EXPECT_EQ(p.diagnose.pairing.mac_min, 0.7);
  EXPECT_EQ(p.diagnose_keys.size(), 8u);

  // The other forms: exp_window by name, pairs = false (--no-pairs), integers for numbers.
  const Project q = ReadProjectFile(OptionsProject("keys2.toml",
      "[frf]\nexp_window = \"none\"\naccept_double_hits = false\n[fit]\nfreq_tol = 1\n"
      "[diagnose]\npairs = false\ncriterion = \"aicc\"\n"));
  EXPECT_EQ(q.frf.impact.exp_window, acquisition::ExpWindowMode::kNone);
  EXPECT_TRUE(q.frf.impact.reject_double_hits);
  EXPECT_EQ(q.fit.stability.frequency_tol, 1.0);
  EXPECT_EQ(q.diagnose.max_effects, 1);
  EXPECT_EQ(q.diagnose.criterion, diagnose::Criterion::kAicc);
  EXPECT_EQ(ReadProjectFile(OptionsProject("keys3.toml", "[diagnose]\npairs = true\n")).diagnose.max_effects, 3);
  const Project shapes = ReadProjectFile(
      OptionsProject("keys5.toml", "[diagnose]\nshape_residual = \"mac\"\nshape_dof_sigma = 0.2\n"));
  EXPECT_EQ(shapes.diagnose.shape_residual, diagnose::ShapeResidual::kOneMinusMac);
  EXPECT_EQ(shapes.diagnose.shape_dof_sigma, 0.2);
  EXPECT_EQ(ReadProjectFile(OptionsProject("keys4.toml", "[frf]\nexp_window = 0\n")).frf.impact.exp_window,
            acquisition::ExpWindowMode::kFixed);  // as --exp-window 0
}

// A bad value is an InputError at its line naming the table, the key and what was expected (or
// what the options struct's own check says).
TEST(ProjectFile, BadOptionValuesNameTheLineTableAndKey) {
  struct Case {
    std::string tables;
    std::vector<std::string> expected;  // all in the message
  };
  const std::vector<Case> cases = {
      {"[frf]\nestimator = \"H3\"\n", {"bad.toml:6", "[frf] estimator", "H3", "H1, H2 or Hv"}},
      {"[frf]\nestimator = 1\n", {"bad.toml:6", "[frf] estimator: expected a string"}},
      {"[frf]\nexp_window = \"sometimes\"\n", {"bad.toml:6", "[frf] exp_window: expected \"auto\", \"none\" or a decay rate"}},
      {"[frf]\nexp_window = -3.0\n", {"bad.toml:6", "[frf] exp_window", "(--exp-window)", ">= 0"}},
      {"[frf]\nquantity = \"velocity\"\n", {"bad.toml:6", "[frf] quantity: expected accelerance, mobility or receptance, got 'velocity'"}},
      {"[frf]\ntrigger_level = 1.5\n", {"bad.toml:6", "[frf] trigger_level", "(--trigger-level)"}},
      {"[frf]\nband = [800, 5]\n", {"bad.toml:6", "[frf] band: expected [low_hz, high_hz] with 0 <= low < high"}},
      {"[frf]\nthreads = -1\n", {"bad.toml:6", "[frf] threads", "(--threads)"}},
      {"[frf]\naccept_double_hits = \"yes\"\n", {"bad.toml:6", "[frf] accept_double_hits: expected true or false"}},
      {"[fit]\norder_max = 0\n", {"bad.toml:6", "[fit] order_max: expected a positive integer"}},
      {"[fit]\norder_max = 4.5\n", {"bad.toml:6", "[fit] order_max: expected a positive integer"}},
      {"[fit]\nband = [600.0]\n", {"bad.toml:6", "[fit] band: expected [low_hz, high_hz]"}},
      {"[fit]\nmethod = \"lscf\"\n", {"bad.toml:6", "[fit] method: expected polymax or peak, got 'lscf'"}},
      {"[fit]\nrefine = \"yes\"\n", {"bad.toml:6", "[fit] refine: expected ml or none, got 'yes'"}},
      {"[fit]\nfreq_tol = \"1 %\"\n", {"bad.toml:6", "[fit] freq_tol: expected a number"}},
      {"[fit]\nfreq_tol = nan\n", {"bad.toml:6", "[fit] freq_tol: expected a number"}},
      {"[fit]\ndamping_tol = 0\n", {"bad.toml:6", "[fit] damping_tol", "(--damping-tol) must be > 0"}},
      {"[fit]\nmac_min = 1.2\n", {"bad.toml:6", "[fit] mac_min", "(--mac-min) must lie in [0, 1]"}},
      {"[fit]\nthreads = 2.0\n", {"bad.toml:6", "[fit] threads: expected an integer"}},
      {"[fit]\nselect = \"196.4;267\"\n", {"bad.toml:6", "'select'", "196.4;267"}},
      {"[fit]\nselect = \"\"\n", {"bad.toml:6", "'select'"}},
      {"[fit]\nselect = \"auto,196.4\"\n", {"bad.toml:6", "'select'", "got 'auto'"}},
      {"[diagnose]\ncriterion = \"aic\"\n", {"bad.toml:6", "[diagnose] criterion: expected evidence, bic or aicc, got 'aic'"}},
      {"[diagnose]\nmax_effects = 0\n", {"bad.toml:6", "[diagnose] max_effects", "max_effects must be 1, 2 or 3"}},
      {"[diagnose]\nmax_effects = 4\n", {"bad.toml:6", "[diagnose] max_effects", "max_effects must be 1, 2 or 3"}},
      {"[diagnose]\nfrequency_floor = -1e-3\n", {"bad.toml:6", "[diagnose] frequency_floor", "frequency_floor must be > 0"}},
      {"[diagnose]\nshape_sigma = 0\n", {"bad.toml:6", "[diagnose] shape_sigma", "shape_sigma must be > 0"}},
      {"[diagnose]\nshape_residual = \"per_dof\"\n", {"bad.toml:6", "[diagnose] shape_residual: expected mac or per-dof, got 'per_dof'"}},
      {"[diagnose]\nshape_dof_sigma = 0\n", {"bad.toml:6", "[diagnose] shape_dof_sigma", "shape_dof_sigma must be > 0"}},
      {"[diagnose]\neffect_prior_odds = 2\n", {"bad.toml:6", "[diagnose] effect_prior_odds", "(0, 1]"}},
      {"[diagnose]\nmac_min = -0.1\n", {"bad.toml:6", "[diagnose] mac_min", "mac_min (--mac-min) must lie in [0, 1]"}},
      {"[diagnose]\nexact_form = 1\n", {"bad.toml:6", "[diagnose] exact_form: expected true or false"}},
      {"[diagnose]\nmembers = \"no\"\n", {"bad.toml:6", "[diagnose] members: expected true or false"}},
      {"[diagnose]\nmax_effects = 3\npairs = false\n", {"bad.toml:7", "[diagnose] pairs = false and max_effects = 3: give one"}},
      // Unknown keys name the key, its line and the keys allowed there.
      {"[fit]\norder_min = 4\n", {"bad.toml:6", "unknown key 'order_min' in [fit]", "allowed: args, band, damping_tol"}},
      {"[diagnose]\nno_pairs = true\n", {"bad.toml:6", "unknown key 'no_pairs' in [diagnose]", "pairs"}},
      {"[frf]\nbinary = true\n", {"bad.toml:6", "unknown key 'binary' in [frf]", "estimator"}},
  };
  for (const Case& c : cases) {
    const std::string what = ReadError(OptionsProject("bad.toml", c.tables));
    EXPECT_FALSE(what.empty()) << c.tables << " accepted";
    for (const std::string& e : c.expected) EXPECT_NE(what.find(e), std::string::npos) << c.tables << "\n" << what;
  }
}

// args, the old form, still reads verbatim; a key and the same option in args is refused, naming
// both (--name, --name=value, and an abbreviation the command-line parser would take for it).
TEST(ProjectFile, ArgsStillReadButNotWithTheSameKey) {
  const Project p = ReadProjectFile(OptionsProject("args.toml",
      "[fit]\norder_max = 40\nargs = [\"--freq-tol\", \"0.02\", \"--refine=none\"]\n"
      "[diagnose]\ncriterion = \"bic\"\nargs = [\"--max-effects\", \"2\"]\n"));
  EXPECT_EQ(p.fit_extra, (std::vector<std::string>{"--freq-tol", "0.02", "--refine=none"}));
  EXPECT_EQ(p.diagnose_extra, (std::vector<std::string>{"--max-effects", "2"}));
  EXPECT_EQ(p.fit.polymax.order_max, 40);
  EXPECT_EQ(p.fit.stability.frequency_tol, curvefit::FitOptions().stability.frequency_tol);  // args are not read here
  EXPECT_EQ(p.fit_keys, (std::vector<std::string>{"order_max"}));

  const std::vector<std::pair<std::string, std::vector<std::string>>> cases = {
      {"[fit]\norder_max = 40\nargs = [\"--order-max\", \"30\"]\n", {"bad.toml:6", "[fit] order_max and args --order-max: give one"}},
      {"[fit]\nargs = [\"--band=1:2\"]\nband = [1.0, 2.0]\n", {"bad.toml:7", "[fit] band and args --band: give one"}},
      {"[fit]\nselect = \"auto\"\nargs = [\"--select\", \"200\"]\n", {"bad.toml:6", "[fit] select and args --select"}},
      {"[fit]\nfreq_tol = 0.02\nargs = [\"--freq\", \"0.03\"]\n", {"bad.toml:6", "[fit] freq_tol and args --freq (--freq-tol): give one"}},
      {"[diagnose]\ncriterion = \"bic\"\nargs = [\"--criterion=aicc\"]\n", {"bad.toml:6", "[diagnose] criterion and args --criterion"}},
      {"[diagnose]\npairs = false\nargs = [\"--no-pairs\"]\n", {"bad.toml:6", "[diagnose] pairs and args --no-pairs"}},
      {"[diagnose]\nmax_effects = 2\nargs = [\"--no-pairs\"]\n", {"bad.toml:6", "[diagnose] max_effects and args --no-pairs"}},
      {"[diagnose]\nmembers = false\nargs = [\"--no-members\"]\n", {"bad.toml:6", "[diagnose] members and args --no-members"}},
      {"[diagnose]\nexact_form = true\nargs = [\"--exact-form\"]\n", {"bad.toml:6", "[diagnose] exact_form and args --exact-form"}},
      {"[diagnose]\nshape_sigma = 0.02\nargs = [\"--shape-weight\", \"0.1\"]\n", {"bad.toml:6", "[diagnose] shape_sigma and args --shape-weight"}},
      {"[diagnose]\nmac_min = 0.7\nargs = [\"--mac-min\", \"0.6\"]\n", {"bad.toml:6", "[diagnose] mac_min and args --mac-min"}},
      {"[fit]\nargs = \"--order-max 30\"\n", {"bad.toml:6", "'args' must be an array of strings"}},
  };
  for (const auto& [tables, expected] : cases) {
    const std::string what = ReadError(OptionsProject("bad.toml", tables));
    EXPECT_FALSE(what.empty()) << tables << " accepted";
    for (const std::string& e : expected) EXPECT_NE(what.find(e), std::string::npos) << tables << "\n" << what;
  }
  // An option no key of the table gives, or an option the table has no key for, is no conflict.
  EXPECT_EQ(ReadError(OptionsProject("ok.toml", "[fit]\nfreq_tol = 0.02\nargs = [\"--damping-tol\", \"0.1\", \"--plot\", \"x.svg\"]\n")), "");
}

}  // namespace
}  // namespace ema::formats
