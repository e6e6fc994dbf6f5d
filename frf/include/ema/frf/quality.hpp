// Data-quality checks on measured FRFs, before any fitting: reciprocity, driving points, the
// coherence map and the impact-to-impact scatter. Each check returns numbers and a pass/warn
// verdict with its reason (the mode-complexity checks of fitted modes live in
// ema/curvefit/complexity.hpp). No file I/O: `ema quality` reads the files and prints the report.
//
// Conventions: an FRF is identified by (response DOF, reference DOF). DOFs given with a negative
// direction code (e.g. 3-Z) are turned to the positive one with the FRF's sign changed, so
// H(3-Z, 1+Z) and H(3+Z, 1+Z) describe the same measurement up to sign.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "ema/core/types.hpp"

namespace ema::frf {

enum class Verdict { kPass, kWarn };

/// "pass" / "warn".
std::string VerdictToString(Verdict verdict);

struct QualityOptions {
  /// Band of the checks [Hz]; band_hi_hz <= 0 means up to the last line. DC is always skipped.
  double band_lo_hz = 0.0;
  double band_hi_hz = 0.0;
  /// Reciprocity: a pair passes when ||H_ij - H_ji|| / mean(||H_ij||, ||H_ji||) over the band
  /// stays at or below this (0.05 = 5 %; noise of a good hammer test gives 1-3 %).
  double reciprocity_tolerance = 0.05;
  /// Driving point: a resonance is a local maximum of |H| above this fraction of the FRF's
  /// largest |H| in the band, in quadrature (|Im A| >= 0.7 |A|: phase within ~45 deg of +-90).
  double resonance_level = 0.1;
  /// Coherence: an FRF passes when the fraction of band lines with coherence below
  /// coherence_min stays at or below coherence_max_low_fraction (anti-resonances are expected
  /// to dip, hence a fraction and not a minimum).
  double coherence_min = 0.9;
  double coherence_max_low_fraction = 0.2;
  /// Scatter: an FRF passes when the median over the band of the normalised random error of
  /// |H| (Bendat & Piersol, eps = sqrt(1 - g2) / (sqrt(g2) sqrt(2 n))) stays at or below this.
  double scatter_max = 0.1;

  bool IsValid(std::string* error) const;
};

/// H_ij against H_ji: the same pair measured both ways (several references, or a roving-hammer
/// file beside a roving-sensor file).
struct ReciprocityCheck {
  Dof dof_i, dof_j;              ///< H_ij = response at i, force at j
  double relative_difference = kNaN;  ///< ||H_ij - H_ji||_2 / (0.5 (||H_ij|| + ||H_ji||)) over the band
  double amplitude_ratio = kNaN; ///< ||H_ij|| / ||H_ji||
  Verdict verdict = Verdict::kPass;
  std::string reason;
};

/// A driving-point FRF (response DOF = reference DOF). For a passive structure Re of the
/// mobility is >= 0 at every frequency (e^{+jwt}), so Im of the accelerance is >= 0, Im of the
/// receptance <= 0; the check looks at the sign at each resonance peak.
struct DrivingPointCheck {
  Dof dof;
  int resonances = 0;            ///< peaks examined
  int flipped = 0;               ///< peaks with the wrong sign
  std::vector<double> flipped_frequencies_hz;
  double sign_consistency = kNaN;  ///< sum(w s)/sum(w), s = +1 right sign, w = (signed part)^2: +1 good, -1 inverted
  Verdict verdict = Verdict::kPass;
  std::string reason;
};

/// Coherence and the impact-to-impact scatter of one FRF.
struct FrfStatistics {
  Dof response, reference;
  double mean_coherence = kNaN;
  double low_coherence_fraction = kNaN;  ///< fraction of band lines with coherence < coherence_min
  int averages = 0;                      ///< accepted impacts (0 when unknown)
  double median_random_error = kNaN;     ///< median over the band of eps(|H|); NaN without coherence/averages
  double max_random_error = kNaN;        ///< largest eps(|H|) over the band
  Verdict coherence_verdict = Verdict::kPass;
  Verdict scatter_verdict = Verdict::kPass;
  std::string reason;            ///< empty when both pass
};

/// Every FRF × every band line: the numbers behind a coherence picture.
struct CoherenceMap {
  Eigen::VectorXd frequency_hz;  ///< band lines
  std::vector<std::string> labels;  ///< "RESPONSE/REFERENCE" per row
  Eigen::MatrixXd coherence;     ///< rows = FRFs (as labels), columns = band lines; NaN unknown
};

struct FrfQualityReport {
  std::vector<ReciprocityCheck> reciprocity;
  std::vector<DrivingPointCheck> driving_points;
  std::vector<FrfStatistics> frfs;
  CoherenceMap coherence_map;    ///< empty when no set carries coherence
  bool has_coherence = false;
  bool has_averages = false;
  std::vector<std::string> notes;  ///< what could not be checked and why

  /// kWarn when any check warns.
  Verdict Overall() const;
  int WarningCount() const;
};

/// Runs every FRF check on one or more FRF sets of the same structure (e.g. a roving-hammer and
/// a roving-sensor file). Sets must share the frequency grid (InputError otherwise, naming
/// `sources[k]`); FRFs measured twice are compared (reciprocity needs different DOFs; the same
/// FRF twice is ignored for reciprocity and the first one is used).
FrfQualityReport CheckFrfQuality(const std::vector<FrfSet>& sets, const QualityOptions& options = {},
                                 const std::vector<std::string>& sources = {});

/// Normalised random error of an H1 magnitude estimate from coherence g2 and n averages
/// (Bendat & Piersol, Random Data, eq. 9.73): sqrt(1 - g2) / (sqrt(g2) sqrt(2 n)).
double RandomErrorOfMagnitude(double coherence, int averages);

}  // namespace ema::frf
