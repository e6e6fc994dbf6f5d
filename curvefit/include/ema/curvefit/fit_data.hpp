// Band selection, reciprocity transpose, NaN-line screening and per-output weighting of an FrfSet:
// the common input of PolyMAX, LSFD and peak picking.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "ema/core/types.hpp"

namespace ema::curvefit {

/// FRFs of one test in the orientation the estimators use: `l` outputs (rows of the RMFD, mode
/// shape DOFs) by `m` references (participation DOFs), only the lines inside the band.
struct FitData {
  Eigen::VectorXd frequency_hz;    ///< lines in the band (uniform spacing)
  double line_spacing_hz = 0.0;
  std::vector<Dof> outputs;        ///< l shape DOFs (hammer points when transposed)
  std::vector<Dof> references;     ///< m reference DOFs (fixed sensors when transposed)
  /// n_lines × (l·m); column o·m + i is H_oi. Lines skipped for NaN hold 0 and line_weight 0.
  Eigen::MatrixXcd h;
  Eigen::VectorXd line_weight;     ///< 1 for used lines, 0 for skipped (NaN) lines
  Eigen::VectorXd output_weight;   ///< per output: 1/RMS over the band and references
  /// n_lines × (l·m): variance E|dH|^2 of each FRF line from its coherence and averages,
  /// |H|^2 (1 - coh) / (n_avg coh) (algorithms.md §1.8); NaN where unknown (coherence missing or
  /// not in (0, 1], fewer than 2 averages). Empty when the set carries no coherence at all.
  Eigen::MatrixXd noise_variance;
  FrfType frf_type = FrfType::kAccelerance;
  double window_decay_rate = 0.0;  ///< 1/tau, added to every estimated pole (algorithms.md §1.4)
  bool transposed = false;         ///< roles swapped by reciprocity (roving hammer)
  /// Per output: the roving set it was measured in (FrfSet::output_sets); empty when unknown or
  /// transposed. Each set's sensors load the article while it is measured, so each set sees every
  /// mode at a slightly different frequency.
  std::vector<int> output_set;
  std::vector<std::string> warnings;

  /// The roving sets, in order of their ids (empty when unknown): the outputs of each.
  std::vector<std::vector<int>> SetOutputs() const;

  int LineCount() const { return static_cast<int>(frequency_hz.size()); }
  int UsedLineCount() const { return static_cast<int>(line_weight.sum()); }
  int OutputCount() const { return static_cast<int>(outputs.size()); }
  int ReferenceCount() const { return static_cast<int>(references.size()); }
  std::complex<double> H(int line, int output, int reference) const {
    return h(line, output * ReferenceCount() + reference);
  }
};

struct FitDataOptions {
  double band_lo_hz = 0.0;        ///< lower band edge; lines below are dropped (DC is always dropped)
  double band_hi_hz = 0.0;        ///< upper band edge; <= 0 means up to the last line
  /// Isolated NaN lines (any FRF NaN) are skipped with a warning when they are at most this
  /// fraction of the band and no run is longer than max_nan_run; otherwise InputError.
  double max_nan_fraction = 0.05;
  int max_nan_run = 3;
  /// Transpose (reciprocity) when the set says roving_hammer, or when it has more references
  /// than outputs (a single fixed sensor and a roving hammer is the common hammer test).
  bool auto_transpose = true;
};

/// Validates and rearranges `frfs`. `source` names the input in error messages. Throws
/// InputError: inconsistent references (h count/shape), no lines in the band, an FRF missing
/// entirely, widespread NaN lines.
FitData PrepareFitData(const FrfSet& frfs, const FitDataOptions& options, const std::string& source = "FRF set");

/// The same data restricted to the given outputs (in that order): one roving set's FRFs.
FitData SubsetOutputs(const FitData& data, const std::vector<int>& outputs);

}  // namespace ema::curvefit
