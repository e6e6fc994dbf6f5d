// Test–model correlation: DOF matching, MAC matrix, pairing, frequency agreement, COMAC and the
// validation table (issue 5). Pure computation; the table is returned as text and the caller
// writes it (formats/app do the file I/O).
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "ema/core/names.hpp"
#include "ema/core/types.hpp"
#include "ema/correlation/dof_match.hpp"
#include "ema/correlation/pairing.hpp"

namespace ema::correlation {

struct CorrelationOptions {
  PairingOptions pairing;
  DofMatchOptions dofs;
  /// Test damping ratio above which a mode is remarked "interface-dominated" (thesis §7.5:
  /// the modes governed by the air film/joints showed 1–5 % damping, the structure < 1 %).
  double interface_damping_ratio = 0.01;

  /// True when every option is in range; else false with the violated condition in *why.
  bool IsValid(std::string* why) const {
    if (!pairing.IsValid(why)) return false;
    if (!(dofs.tolerance_m >= 0.0)) return *why = "dofs.tolerance_m (--tolerance) must be >= 0", false;
    if (!(interface_damping_ratio >= 0.0)) return *why = "interface_damping_ratio (--interface-damping) must be >= 0", false;
    return true;
  }
};

/// One row of the validation table.
struct CorrelationRow {
  int test_mode = -1;                 ///< index into the test modes, -1 for model-only
  int model_mode = -1;                ///< index into the model modes, -1 for test-only
  double test_frequency_hz = kNaN;
  double test_damping_ratio = kNaN;
  double model_frequency_hz = kNaN;
  double agreement_pct = kNaN;        ///< 100 (1 − |f_m − f_t| / f_m)
  double frequency_error_pct = kNaN;  ///< (f_m − f_t) / f_t · 100
  double mac = kNaN;
  /// The test mode's complexity as the fit computed it (Mode::mpc, mpd, mcf; NaN when the test
  /// modes' file does not carry it): MPC 0..1 (1 = real), MPD [deg] (0 = real), MCF 0..1 (0 = real).
  double test_mpc = kNaN;
  double test_mpd_deg = kNaN;
  double test_mcf = kNaN;
  std::string remark;                 ///< "paired", "test-only", "model-only" [+ "; interface-dominated"] [+ "; order swap"]
  bool paired() const { return test_mode >= 0 && model_mode >= 0; }
};

struct ComacEntry {
  Dof dof;       ///< the test DOF
  double comac;  ///< 0..1, low = the model disagrees here
};

struct CorrelationResult {
  int shared_dof_count = 0;
  int test_dof_count = 0;
  DofMatch dof_match;
  Eigen::MatrixXd mac;           ///< n_test × n_model over the shared DOFs
  Eigen::MatrixXd automac_test;  ///< over the shared DOFs
  Eigen::MatrixXd automac_model;
  Pairing pairing;
  std::vector<CorrelationRow> rows;  ///< paired and model-only by model frequency, then test-only
  std::vector<ComacEntry> comac;     ///< over the paired modes, worst (lowest) first
  double mean_agreement_pct = kNaN, min_agreement_pct = kNaN, mean_mac = kNaN;
  double mean_abs_frequency_error_pct = kNaN;  ///< mean |f_m − f_t| / f_t · 100 over the pairs
};

/// Correlates test modes with model modes. Throws InputError (naming the sets' `source`) when a
/// set holds no modes, when a mode's shape does not match its set's DOF list, or when the sets
/// share no DOF.
CorrelationResult Correlate(const ModeSet& test, const ModeSet& model, const CorrelationOptions& options = {});

enum class TableFormat { kMarkdown, kCsv, kHtml };
/// `ema correlate --table FILE`: the format by the file's extension (lower case).
inline constexpr EnumName<TableFormat> kTableFormatExtensions[] = {
    {TableFormat::kMarkdown, ".md"}, {TableFormat::kCsv, ".csv"}, {TableFormat::kHtml, ".html"}, {TableFormat::kHtml, ".htm"}};

/// The validation table (mode, model f, test f and damping, agreement %, Δf %, MAC, the test
/// mode's MPC, MPD and MCF, remark) followed by the COMAC list, as text in the requested format.
std::string FormatCorrelationTable(const CorrelationResult& result, TableFormat format);

}  // namespace ema::correlation
