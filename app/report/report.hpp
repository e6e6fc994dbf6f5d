// The self-contained HTML report of `ema run`: one file with every chart (plotly.js embedded), the
// data it draws embedded as JSON, and no network access when opened.
//
// The input is the run's typed result (pipeline::RunResult: the measured FRFs, the fit with its
// own modal model, the model modes, the correlations, the diagnosis and its findings), so the
// report shows exactly what the stages produced and computes nothing of its own: the MAC is the
// correlation's, the fit curve is the fit's modal model (curvefit::SynthesiseMeasuredFrf), the
// first screen words the diagnosis's findings (pipeline::Findings). No text the program wrote is
// read back, and the terminal's summary is not part of the page.
#pragma once

#include <Eigen/Core>
#include <complex>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "ema/core/types.hpp"
#include "ema/correlation/correlate.hpp"
#include "ema/curvefit/fit.hpp"
#include "ema/pipeline/run.hpp"

namespace ema::report {

/// A correlation with the mode sets it correlated (the MAC chart's rows and columns).
struct CorrelationView {
  correlation::CorrelationResult result;
  ModeSet test;                        ///< the test modes as correlated
  ModeSet model;                       ///< the model's modes
};

/// Everything the report shows about one test (one setup of the model).
struct SetupResults {
  std::string name;                    ///< setup name ("stud-5um"), or the test's name
  std::optional<FrfSet> frfs;          ///< measured FRFs (ema frf output), if available
  nlohmann::json frf_summary;          ///< `ema frf --json` (averages, rejected impacts)
  nlohmann::json stabilisation;        ///< `ema fit --stabilisation`
  nlohmann::json quality;              ///< `ema quality --json` layout (data-quality section)
  /// The fit: its modes (animated shapes, mode table), the poles it dropped, its refinement and
  /// its own modal model (the fit curve over the measured FRFs). Empty: no fit.
  std::optional<curvefit::FitResult> fit;
  curvefit::RefineMethod refine = curvefit::RefineMethod::kMl;  ///< how the fit refined (mode table)
  std::optional<CorrelationView> correlation_before;  ///< with the nominal model
  std::optional<CorrelationView> correlation_after;   ///< with the updated model
  std::vector<Node> geometry;          ///< test points (m), for the animated shapes
  std::vector<std::pair<int, int>> lines;  ///< wireframe edges between test points (node ids)
  /// The pole selection the fit used: {"select": "auto" | "F1,F2,...", "by_hand": true when picked
  /// in `ema pick` during the run, "rule": FitResult::selection_rule, "command": the equivalent
  /// `ema fit` line, "modes_json": the modes file relative to the report}. Null: not shown.
  nlohmann::json selection;
  std::string rehearsal;               ///< a simulated test: report::RehearsalWords ("" measured)
  double sensor_mass_kg = 0.0;         ///< the test's own sensors per measured node ([[test]] sensor_mass)
  double band_lo_hz = 0.0;             ///< fit band; 0/0 = the whole FRF range
  double band_hi_hz = 0.0;
};

struct ReportInput {
  std::string title = "ema report";
  std::string subtitle;                ///< e.g. the project file and the date
  std::vector<std::string> steps;      ///< the files each step wrote, for the "files" list
  std::vector<SetupResults> setups;
  /// The diagnosis (pipeline::DiagnoseStage): DIAG.json's data and the first screen. Empty: none.
  std::optional<pipeline::DiagnoseStage> diagnosis;
  /// `ema amplitude --json` (cli.md) when the test was run at several force levels: the report
  /// then plots frequency and damping against level per mode. Null: no such section.
  nlohmann::json amplitude;
  /// Where rank 1's effects act (DiagnosedPlaces): drawn over the test geometry.
  nlohmann::json diagnosed_places;
  /// OUTDIR/history.json (app::AppendRunHistory): the model versions of successive runs.
  nlohmann::json history;
  std::vector<std::string> problems;   ///< steps that failed or were skipped, shown in the page
  /// When rank 1 has look-alikes, the test that tells them apart (pipeline::NextTest): {"test",
  /// "readings", "sets": [[{"node", "dir"}, ...], ...] (the test's own first), "kept_sets",
  /// "references": [{"node", "dir"}], "separations": [{"a", "b", "sigma_before", "sigma_after"}],
  /// "automac_max_offdiagonal"}, or {"error"} when it could not be planned. Null: none.
  nlohmann::json next_test;
};

/// What the page of a run shows beside its result: facts of the output folder.
struct RunPage {
  std::string subtitle;                ///< e.g. the project file, the model and the date
  std::vector<std::string> files;      ///< the files the run wrote, relative to OUTDIR
  nlohmann::json history;              ///< OUTDIR/history.json after this run
  std::vector<std::string> fit_commands;  ///< per test: the equivalent `ema fit` line ("" when none)
  std::vector<std::string> problems;   ///< the run's problems in words (app::RunProblems)
};

/// The report of a run: everything from `run` and the page's facts.
ReportInput ReportInputOf(const pipeline::RunResult& run, const RunPage& page);
std::string RenderHtml(const pipeline::RunResult& run, const RunPage& page);

/// Where `effects` (rank 1's) act on the model: [{"target", "kind", "label", "points": [[x,y,z], ...]}]
/// (spring targets: both ends of every spring of the group or member; points: the test points;
/// bodies: the centre; FE parts: none).
nlohmann::json DiagnosedPlaces(const model::Model& model, const std::vector<model::Effect>& effects);

/// The complete page. Deterministic for a given input (no timestamps added here).
std::string RenderHtml(const ReportInput& input);

/// The data object the page's script draws from (exposed for tests).
nlohmann::json BuildReportData(const ReportInput& input);

// ---- pieces of the data preparation, exposed for tests ----

/// Normalised stabilisation diagram: one entry per pole (order, frequency, damping, stable flag).
struct StabilisationPoints {
  std::vector<int> order;
  std::vector<double> frequency_hz;
  std::vector<double> damping_ratio;
  std::vector<std::string> status;     ///< "stable" or what failed ("unstable", "f", "fd", ...)
};
StabilisationPoints ReadStabilisation(const nlohmann::json& stabilisation);

/// The diagnosis as the page shows it; nothing is re-computed, only read from the typed result,
/// folded and put into words:
///  - "story": the first screen — rank 1's effects (pipeline::Findings: each with its summed
///    probability, "any": the same effect on any member or point, and its values in engineering
///    units), the mean error and MAC before → after, the adequacy to the test's noise in words,
///    the model's own error where it dominates, the test modes rank 1 still misses
///    ("failing_modes"), the look-alike readings (Findings::lookalikes) and rank 1's flags.
///  - "groups": the candidates with look-alikes folded — one row per group (its best member's
///    values, "more" members, the group's summed probability), the other members under "members".
///  - "modes": per test mode of each setup, the evidence (Findings::modes) with its verdict.
nlohmann::json DiagnosisView(const pipeline::DiagnoseStage& diagnosis);

}  // namespace ema::report
