// The project file of `ema run` (TOML, docs/project-file.md): which model, which tests (setup →
// time data files), and the options of each step.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "ema/core/types.hpp"

namespace ema::formats {

/// One test of the project: a setup of the model and its measured data.
struct ProjectTest {
  std::string setup;                           ///< a [[setup]] name of the model ("" = no setups)
  std::string name;                            ///< folder name in OUT/ (defaults to the setup)
  std::vector<std::filesystem::path> time;     ///< time data files (roving sets), absolute
  std::optional<std::filesystem::path> frf;    ///< FRF file instead of time data (skips `ema frf`)
  /// Mass of the transducer at each measured node, kg (one triaxial accelerometer counts once):
  /// the test's own sensors, which the model's prediction of this test carries (cli.md, added
  /// turn 3). 0: none declared.
  double sensor_mass = 0.0;
  /// This test's pole selection, as `ema fit --select` takes it ("auto" or "F1,F2,..." in Hz):
  /// a pick made in `ema pick`, repeated without the browser. Empty: [fit] select.
  std::string select;
  /// pick = true: `ema run` opens `ema pick` for this test after its fit and goes on with the
  /// selection on screen when the page's Done is pressed (docs/pick.md; `ema run --no-pick` skips it).
  bool pick = false;
};

struct Project {
  std::filesystem::path file;                  ///< the project file itself
  std::string name;                            ///< [project] name (defaults to the file stem)
  std::filesystem::path model;                 ///< absolute path of the model file
  std::vector<ProjectTest> tests;
  // [frf]
  std::string estimator = "H1";
  // [fit]
  std::optional<std::pair<double, double>> band_hz;
  std::optional<int> order_max;
  std::string select = "auto";
  std::vector<std::string> fit_extra;          ///< further `ema fit` options, parsed by the run
  // [diagnose]
  std::vector<std::string> diagnose_extra;     ///< further `ema diagnose` options, parsed by the run
  // [report]
  std::string title;                           ///< defaults to the project name
  std::vector<std::pair<int, int>> lines;      ///< wireframe edges between test points
  bool binary = false;                         ///< [output] binary = true: the FRF files are 58b
};

/// Reads and checks a project file. Relative paths are resolved against the file's folder.
/// InputError ("file:line: what") for a missing file, bad TOML, an unknown key (with the keys
/// allowed there), a wrong type, no [[test]], or a data file that does not exist.
Project ReadProjectFile(const std::filesystem::path& path);

}  // namespace ema::formats
