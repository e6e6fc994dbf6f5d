// Planning a hammer test from the model (docs/plan.md): sensor DOFs chosen by effective
// independence (Kammer 1991) refined by exchange, grouped into roving sets; hammer references
// that excite every target mode; sample rate, record length, hammer tip and impacts from the band
// and the modes' damping; and, given competing readings of a diagnosis (look-alikes), the sensors
// that make their predicted test results differ most, in units of the expected noise.
#pragma once

#include <Eigen/Core>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "ema/core/types.hpp"
#include "ema/model/model.hpp"

namespace ema::planning {

struct PlanOptions {
  std::string setup;  ///< the model setup the test is made in ("" = nominal)
  /// The band whose modes the test must see, Hz. Unset (both 0): 0 to 1.25 × the frequency of
  /// the `default_modes`-th elastic mode, or of the last one below a gap of more than 3× between
  /// two modes (what lies beyond is another regime, out of a hammer's reach).
  double band_lo_hz = 0.0, band_hi_hz = 0.0;
  int default_modes = 6;
  int sensors_per_set = 4;  ///< accelerometers mounted at once (points with `triaxial`, else DOFs)
  int sets = 1;             ///< roving sets; sensors_per_set × sets points (or DOFs) are measured
  bool triaxial = false;    ///< each sensor measures X, Y and Z at one test point
  int references = 1;       ///< hammer DOFs
  /// A mode is excited by a reference when the reference's squared amplitude in it is at least
  /// this share of the mode's largest over the candidate DOFs (a hammer near a node line is not).
  double min_reference_participation = 0.1;
  /// The AutoMAC of the chosen set the exchange keeps below (or does not make worse).
  double automac_limit = 0.1;
  /// Expected noise of the test the separations are measured in (the diagnosis's defaults,
  /// DiagnoseOptions::frequency_floor and shape_dof_sigma): 1σ of a frequency relative to it, and
  /// 1σ of a shape at one DOF relative to the shape's rms amplitude over the set's DOFs.
  double frequency_sigma_rel = 1e-3;
  double shape_dof_sigma = 0.1;
  /// The model's own error the diagnosis inferred (DIAG.json `model_error` of rank 1, where it
  /// dominates the test's σ): each reading is a model, and a test result lies from any model by
  /// the model's error as well as by the noise, so the separations are measured in both combined
  /// — √(σ_f² + ε_f²) of a frequency, √(σ_s² + ε_s²) of a shape per DOF in the units above
  /// (docs/plan.md). 0: the noise alone (a model taken as exact, or no diagnosis).
  double frequency_model_error_rel = 0.0;
  double shape_model_error = 0.0;
  double sensor_mass_kg = 0.0;  ///< per sensor point, written to the plan (the simulator mounts it)
  int impacts = 5;              ///< impacts per reference and set (averages of H1 and coherence)

  bool IsValid(std::string* why) const;
};

/// One reading of the structure a test should tell apart from others: the model with `effects`.
struct Reading {
  std::string label;   ///< "kind on target" (DIAG.json's kind and target)
  std::vector<model::Effect> effects;
  std::string origin;  ///< where it was read, for messages ("DIAG.json, candidate rank 2")
};

struct PlannedMode {
  double frequency_hz = 0.0;
  double damping_ratio = 0.0;
  /// RMS amplitude of the mode at the chosen sensor DOFs relative to its RMS over every candidate
  /// DOF: 1 = seen as well as by an average sensor, near 0 = the sensors sit on its node lines.
  double observability = 0.0;
  /// The best reference's squared amplitude in this mode over the mode's largest (0..1).
  double reference_participation = 0.0;
  bool excited = false;  ///< reference_participation ≥ min_reference_participation
};

/// How far apart two readings' predicted test results lie, in units of the expected noise:
/// √(Σ ((f_a − f_b)/σ_f)² + Σ ((1 − MAC_S(φ_a, φ_b))/σ_s)²) over the target modes, with the MAC
/// over the sensor DOFs S of a plan.
struct Separation {
  std::string a, b;
  double sigma_before = 0.0;  ///< with the kept plan (--keep), else the plan for the modes alone
  double sigma_after = 0.0;   ///< with the plan written
};

struct TestPlan {
  std::vector<Dof> candidates;               ///< every DOF a sensor could measure
  std::vector<std::vector<Dof>> sets;        ///< the roving sets (kept sets first)
  std::vector<Dof> references;
  std::vector<PlannedMode> modes;            ///< the target modes, by frequency
  Eigen::MatrixXd automac;                   ///< of the target modes over every planned sensor DOF
  double automac_max_offdiagonal = 0.0;
  double band_lo_hz = 0.0, band_hi_hz = 0.0;
  double sample_rate_hz = 0.0;
  int samples = 0;
  double pulse_duration_s = 0.0;             ///< half-sine contact time of the hammer tip
  int impacts = 0;
  double sensor_mass_kg = 0.0;
  std::vector<Separation> separations;       ///< per pair of readings (with readings only)
  /// The 1σ the separations are in: of a frequency (a share of f) and of a shape per DOF (a share
  /// of its rms amplitude) — the noise and the model's own error combined (PlanOptions).
  double separation_frequency_sigma_rel = 0.0, separation_shape_sigma = 0.0;
  bool separations_include_model_error = false;  ///< PlanOptions gave a model error (> 0)
  std::vector<std::string> notes;            ///< what the plan could not satisfy, in words

  std::vector<Dof> Sensors() const;          ///< every set's DOFs, in order
};

/// Sensor DOFs that keep the modes `shapes` (candidates × modes, real) most independent:
/// effective independence (Kammer 1991) deletes the candidate group contributing least to the
/// Fisher information det(ΦᵀΦ) until `count` groups are left, then single exchanges (a chosen
/// group for an unchosen one) are made while they raise det(ΦᵀΦ). `groups` lists the candidate
/// rows measured together (one group per point with triaxial sensors, else one row each);
/// `fixed` groups are always kept. Returns the chosen group indices, sorted.
std::vector<int> ChooseSensorGroups(const Eigen::MatrixXd& shapes, const std::vector<std::vector<int>>& groups,
                                    int count, const std::vector<int>& fixed = {});

/// Plans the test of `model` (see PlanOptions). `readings`: the competing readings to separate
/// (two or more; the sensors then maximise their smallest separation, keeping the AutoMAC within
/// automac_limit); `keep`: roving sets of an earlier plan that stay (new sets are added).
/// InputError naming `model.origin` for a band without a model mode, more sensor points than
/// candidates, or a reading the model cannot take (an effect on a target it does not have).
/// `references`: the hammer DOFs of that earlier plan, kept instead of chosen anew.
TestPlan PlanTest(const model::Model& model, const PlanOptions& options, const std::vector<Reading>& readings = {},
                  const std::vector<std::vector<Dof>>& keep = {}, const std::vector<Dof>& references = {});

}  // namespace ema::planning
