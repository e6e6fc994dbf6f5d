// The self-contained HTML report of `ema run`: one file with every chart (plotly.js embedded), the
// data it draws embedded as JSON, and no network access when opened.
//
// The inputs are the typed results of the pipeline's stages (the measured FRFs, the fit with its
// own modal model, the model modes, the correlations, the diagnosis as `ema diagnose --json`), so
// the report shows exactly what the stages produced and computes nothing of its own: the MAC is
// the correlation's, the fit curve is the fit's modal model (curvefit::SynthesiseMeasuredFrf).
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

/// Normalised stabilisation diagram: one entry per pole (order, frequency, damping, stable flag).
struct StabilisationPoints {
  std::vector<int> order;
  std::vector<double> frequency_hz;
  std::vector<double> damping_ratio;
  std::vector<std::string> status;     ///< "stable" or what failed ("unstable", "f", "fd", ...)
};
StabilisationPoints ReadStabilisation(const nlohmann::json& stabilisation);

/// The diagnosis (`ema diagnose --json`) as the page shows it; nothing is re-computed, only read,
/// folded and put into words:
///  - "story": the first screen — rank 1's effects, each with its summed probability over the
///    candidates that hold it ("effect_probabilities"; "any": the same effect on any member or point
///    of a wildcard) and its value ± σ in engineering units (the summary's words where it gives
///    them); the mean error and MAC before → after; the adequacy to the test's noise in words
///    ("noise_consistent", "reduced_chi2"); the test modes rank 1 still misses ("failing_modes");
///    the look-alike readings, one line per group ("groups", the summary's factor-20 rule); rank 1's
///    flags ("checks").
///  - "groups": the candidates with look-alikes folded — one row per group (its best member's
///    values, "more" members, the group's summed probability), the other members under "members";
///    a candidate no group holds is a row of its own.
///  - "modes": per test mode of each setup, the frequency and shape misfit in σ and the MAC as given
///    and with rank 1, the mode's share of the fall in χ² ("share_pct") and a verdict ("within
///    noise", "marginal" > 2σ, "misfit" > 3σ, "unpaired").
/// Empty object: no diagnosis.
nlohmann::json DiagnosisView(const nlohmann::json& diagnosis);

/// A fitted parameter in engineering units with its 1σ: "E' = 168 ± 0.37 GPa (R' = 1 mm)",
/// "k = 2.8 ± 0.1 N/µm", "m = 10.9 ± 2.6 g", "stiffness × 0.31 ± 0.02". NaN sigma: no "±".
std::string ParameterText(const std::string& kind, const std::string& name, double value, double sigma,
                          double radius_m = std::numeric_limits<double>::quiet_NaN());

}  // namespace ema::report
