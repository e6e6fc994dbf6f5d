// The self-contained HTML report of `ema run`: one file with every chart (plotly.js embedded), the
// data it draws embedded as JSON, and no network access when opened.
//
// The inputs are the files the pipeline steps write (the JSON of `ema frf/fit/model/correlate/
// diagnose`) plus the measured FRFs, so the report shows exactly what the steps produced.
#pragma once

#include <Eigen/Core>
#include <complex>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "ema/core/types.hpp"

namespace ema::report {

/// Everything the report shows about one test (one setup of the model).
struct SetupResults {
  std::string name;                    ///< setup name ("stud-5um"), or the test's name
  std::optional<FrfSet> frfs;          ///< measured FRFs (ema frf output), if available
  nlohmann::json frf_summary;          ///< `ema frf --json` (averages, rejected impacts)
  nlohmann::json stabilisation;        ///< `ema fit --stabilisation`
  nlohmann::json quality;              ///< `ema quality --json` layout (data-quality section)
  nlohmann::json test_modes;           ///< `ema fit --json` ({"modes": [...]})
  nlohmann::json model_modes_before;   ///< `ema model --json` of the nominal model
  nlohmann::json model_modes_after;    ///< `ema model --json` of the updated model
  nlohmann::json correlation_before;   ///< `ema correlate --json`, nominal model
  nlohmann::json correlation_after;    ///< `ema correlate --json`, updated model
  std::vector<Node> geometry;          ///< test points (m), for the animated shapes
  std::vector<std::pair<int, int>> lines;  ///< wireframe edges between test points (node ids)
  double band_lo_hz = 0.0;             ///< fit band; 0/0 = the whole FRF range
  double band_hi_hz = 0.0;
};

struct ReportInput {
  std::string title = "ema report";
  std::string subtitle;                ///< e.g. the project file and the date
  std::vector<std::string> summary;    ///< the run's one-screen summary, one line each
  std::vector<std::string> steps;      ///< the files each step wrote, for the "files" list
  std::vector<SetupResults> setups;
  nlohmann::json diagnosis;            ///< `ema diagnose --json`
  /// `ema amplitude --json` (cli.md) when the test was run at several force levels: the report
  /// then plots frequency and damping against level per mode. Null: no such section.
  nlohmann::json amplitude;
  /// Where rank 1's effects act (app::DiagnosedPlaces): drawn over the test geometry.
  nlohmann::json diagnosed_places;
  /// OUTDIR/history.json (app::AppendRunHistory): the model versions of successive runs.
  nlohmann::json history;
  std::vector<std::string> problems;   ///< steps that failed or were skipped, shown in the page
};

/// The complete page. Deterministic for a given input (no timestamps added here).
std::string RenderHtml(const ReportInput& input);

/// The data object the page's script draws from (exposed for tests).
nlohmann::json BuildReportData(const ReportInput& input);

// ---- pieces of the data preparation, exposed for tests ----

/// A mode shape as read from a modes JSON (cli.md layout), keyed by DOF with positive direction
/// codes (a "-Z" value is stored negated under "+Z").
struct ShapeTable {
  std::vector<Dof> dofs;
  std::vector<double> frequency_hz;
  std::vector<double> damping_ratio;
  Eigen::MatrixXcd shapes;             ///< dofs × modes
};

/// Reads {"modes": [{"frequency_hz", "damping_ratio", "shape": [{"node", "dir", "value"}]}]}.
/// Unknown or missing pieces give an empty table (the report then says the chart is unavailable).
ShapeTable ReadShapeTable(const nlohmann::json& modes_json);

/// The FRF from `reference` to `response` of the fit's own modal model (MODES.json
/// "modal_model" of `ema fit`: poles as fitted, receptance residues, real lower/upper residual
/// terms, FRF type; curvefit.md), on the lines inside the model's band. NaN elsewhere, and
/// everywhere when the model lacks that FRF (nothing is re-fitted here).
Eigen::VectorXcd SynthesiseFromModalModel(const nlohmann::json& modal_model, const Dof& response, const Dof& reference,
                                          const Eigen::VectorXd& frequency_hz);

/// Normalised stabilisation diagram: one entry per pole (order, frequency, damping, stable flag).
struct StabilisationPoints {
  std::vector<int> order;
  std::vector<double> frequency_hz;
  std::vector<double> damping_ratio;
  std::vector<std::string> status;     ///< "stable" or what failed ("unstable", "f", "fd", ...)
};
StabilisationPoints ReadStabilisation(const nlohmann::json& stabilisation);

}  // namespace ema::report
