// The project file of `ema run` (TOML, docs/project-file.md): which model, which tests (setup →
// time data files), and the options of each step.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "ema/core/types.hpp"
#include "ema/curvefit/fit.hpp"
#include "ema/diagnose/diagnose.hpp"
#include "ema/frf/hammer_frf.hpp"

namespace ema::formats {

/// One test of the project: a setup of the model and its measured data.
struct ProjectTest {
  std::string setup;                           ///< a [[setup]] name of the model ("" = no setups)
  std::string name;                            ///< folder name in OUT/ (defaults to the setup)
  std::vector<std::filesystem::path> time;     ///< time data files (roving sets), absolute
  std::optional<std::filesystem::path> frf;    ///< FRF file instead of time data (skips `ema frf`)
  /// plan = "PLAN.toml": a rehearsal — the test is simulated from this plan (docs/plan-format.md,
  /// as `ema simulate` does) instead of read from time data, then run as any other test.
  std::optional<std::filesystem::path> plan;
  /// truth = "MODEL.toml": the model variant the planned test is simulated on (with plan only;
  /// default: the project's model).
  std::optional<std::filesystem::path> truth;
  /// Mass of the transducer at each measured node, kg (one triaxial accelerometer counts once):
  /// the test's own sensors, which the model's prediction of this test carries (cli.md, added
  /// turn 3). 0: none declared.
  double sensor_mass = 0.0;
  /// This test's pole selection, as `ema fit --select` takes it ("auto" or "F1,F2,..." in Hz):
  /// a pick made in `ema pick`, repeated without the browser. Empty: [fit] select.
  std::string select;
  /// The same selection parsed: nullopt when the test gives no select ([fit] select applies), an
  /// empty list for "auto", else the frequencies in Hz (each > 0, as `ema fit --select` takes them).
  std::optional<std::vector<double>> select_hz;
  /// pick = true: `ema run` opens `ema pick` for this test after its fit and goes on with the
  /// selection on screen when the page's Done is pressed (docs/pick.md; `ema run --no-pick` skips it).
  bool pick = false;
};

/// The project and the options of each step. The options of [frf], [fit] and [diagnose] are
/// typed: each key is the TOML form of one option of `ema frf` / `ema fit` / `ema diagnose` (the
/// option's name with '_' for '-', docs/project-file.md), read into that command's options
/// struct over the struct's defaults and validated here, once. A struct whose table gives no key
/// equals a default-constructed one.
struct Project {
  std::filesystem::path file;                  ///< the project file itself
  std::string name;                            ///< [project] name (defaults to the file stem)
  std::filesystem::path model;                 ///< absolute path of the model file
  std::vector<ProjectTest> tests;
  // [frf]
  ::ema::frf::FrfOptions frf;                  ///< `ema frf` options: estimator, band, exp_window, ...
  std::string estimator = "H1";                ///< frf.estimator's name (H1, H2 or Hv)
  std::vector<std::string> frf_keys;           ///< the [frf] keys given (in the order of docs/project-file.md)
  // [fit]
  ::ema::curvefit::FitOptions fit;             ///< `ema fit` options; fit.select_frequencies_hz = select_hz
  std::optional<std::pair<double, double>> band_hz;  ///< band = [lo, hi] as given (also in fit.data)
  std::optional<int> order_max;                ///< order_max as given (also in fit.polymax.order_max)
  std::string select = "auto";                 ///< [fit] select as written ("auto" or "F1,F2,...")
  std::vector<double> select_hz;               ///< the same, parsed: empty = auto
  std::vector<std::string> fit_keys;           ///< the [fit] keys given, args excluded
  /// [fit] args: the old form, `ema fit` options verbatim, for `ema run`'s command-line parser.
  /// None of them is an option that a key given in [fit] sets (ReadProjectFile refuses that).
  std::vector<std::string> fit_extra;
  // [diagnose]
  ::ema::diagnose::DiagnoseOptions diagnose;   ///< `ema diagnose` options: criterion, max_effects, ...
  std::vector<std::string> diagnose_keys;      ///< the [diagnose] keys given, args excluded
  /// [diagnose] args: the old form, `ema diagnose` options verbatim, as [fit] args.
  std::vector<std::string> diagnose_extra;
  // [report]
  std::string title;                           ///< defaults to the project name
  std::vector<std::pair<int, int>> lines;      ///< wireframe edges between test points
  bool binary = false;                         ///< [output] binary = true: the FRF files are 58b
};

/// Reads and checks a project file. Relative paths are resolved against the file's folder.
/// InputError ("file:line: what") for a missing file, bad TOML, an unknown key (with the keys
/// allowed there), a wrong type, no [[test]], or a data file that does not exist.
/// Typed options: a key of the wrong type or out of range ("file:line: [fit] order_max: expected
/// a positive integer"), options the struct's IsValid refuses, and a key given together with
/// the same option in that table's args ("[fit] order_max and args --order-max: give one").
Project ReadProjectFile(const std::filesystem::path& path);

}  // namespace ema::formats
