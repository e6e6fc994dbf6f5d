// Hammer-test simulator: exact modal superposition of half-sine impacts (spec algorithms.md §7.3),
// sampled like a real DAQ (fine grid, identical zero-phase anti-alias FIR on every channel,
// decimation), independent noise on every channel, optional double hits and clipping.
// It is the ground truth generator of the test suites of every later stage.
#pragma once

#include <Eigen/Core>
#include <complex>
#include <cstdint>
#include <functional>
#include <vector>

#include "ema/core/types.hpp"

namespace ema::acquisition {

/// Modal truth of one structure state (e.g. with one sensor set mounted).
/// Receptance: alpha_ij(w) = sum_r psi_ri psi_rj / (a_r (jw - lambda_r)) + the conjugate-pair term.
struct ModalTruth {
  std::vector<Dof> dofs;                        ///< DOFs the shapes are given at (sensors and hammer points)
  std::vector<std::complex<double>> poles;      ///< rad/s, Im > 0
  std::vector<Eigen::VectorXcd> shapes;         ///< per mode, aligned with dofs: psi_r
  std::vector<std::complex<double>> modal_a;    ///< per mode a_r; empty => mass-normalised real modes, a_r = 2j*wd_r

  /// a_r of mode r (2j*Im(lambda_r) when modal_a is empty).
  std::complex<double> ModalA(int r) const;
  /// Index of a DOF in `dofs`; throws std::invalid_argument when absent.
  int IndexOf(const Dof& dof) const;
};

/// Builds a ModalTruth from mass-normalised real mode shapes (columns of `phi`), natural
/// frequencies (Hz) and damping ratios: proportional damping, a_r = 2j*wd_r.
ModalTruth ModalTruthFromRealModes(const std::vector<Dof>& dofs, const Eigen::MatrixXd& phi,
                                   const std::vector<double>& frequency_hz, const std::vector<double>& damping_ratio);

/// Receptance matrix (dofs × dofs) at angular frequency w (rad/s), complete pole–residue sum.
Eigen::MatrixXcd ReceptanceMatrix(const ModalTruth& truth, double w);

/// Analytic FRF from a force at `ref` to the response `quantity` at `out` on `frequency_hz`:
/// receptance × (jw)^k with k = 0/1/2 for displacement/velocity/acceleration.
Eigen::VectorXcd AnalyticFrf(const ModalTruth& truth, const Dof& out, const Dof& ref,
                             const Eigen::VectorXd& frequency_hz, Quantity quantity = Quantity::kAcceleration);

/// The FRF an exponential window e^{-decay_rate t} on force and response measures (spec §1.4):
/// H(jw + decay_rate), i.e. every pole moved left by decay_rate, receptance residues unchanged,
/// and for mobility/accelerance the factor (jw)^k evaluated at jw + decay_rate too (so a fit of
/// windowed accelerance finds residues lambda_r^2 R_r with the *uncorrected* lambda_r).
Eigen::VectorXcd AnalyticFrfShifted(const ModalTruth& truth, const Dof& out, const Dof& ref,
                                    const Eigen::VectorXd& frequency_hz, double decay_rate,
                                    Quantity quantity = Quantity::kAcceleration);

/// A second force pulse added to one impact.
struct DoubleHit {
  int set = 0;              ///< roving-set index (0-based)
  int reference = 0;        ///< index into HammerTestPlan::references
  int impact = 1;           ///< impact number within its point (1-based, as in the records)
  double delay_s = 3e-3;    ///< start of the second pulse after the start of the first
  double ratio = 0.3;       ///< amplitude of the second pulse / the first
};

/// A channel saturating at ±full_scale in one impact (noise added before, like an ADC).
struct Clipping {
  int set = 0;
  int reference = 0;
  int impact = 1;
  Dof channel;              ///< response DOF, or the reference DOF with force = true
  bool force = false;       ///< clip the force channel instead of a response
  double full_scale = 0.0;  ///< in the channel's unit (N, m/s^2, ...)
};

/// How a hammer test is acquired. Roving-accelerometer test: one reference, several roving
/// sets. Roving-hammer test: many references (hammer points), one set of fixed sensors.
struct HammerTestPlan {
  double sample_rate_hz = 4096.0;
  int samples_per_record = 8192;
  double pre_trigger_fraction = 0.05;        ///< where the trigger crossing sits in the record
  std::vector<Dof> references;               ///< hammer DOFs (force applied in their direction)
  std::vector<std::vector<Dof>> roving_sets; ///< response DOFs of each set
  int impacts_per_reference = 5;
  double force_peak_n = 100.0;               ///< nominal peak force
  double force_spread = 0.1;                 ///< peak uniformly in force_peak*(1 ± spread)
  double pulse_duration_s = 1e-3;            ///< half-sine contact time T_c
  double force_noise = 0.0;                  ///< noise rms / clean force rms over the record
  double response_noise = 0.0;               ///< noise rms / clean response rms, per channel
  bool noise_relative_to_peak = false;       ///< true: noise rms relative to the channel's peak instead
  Quantity response_quantity = Quantity::kAcceleration;
  double response_full_scale = kNaN;         ///< written to every response TimeRecord::full_scale
  double force_full_scale = kNaN;            ///< written to every force TimeRecord::full_scale
  bool trigger_jitter = true;                ///< pulse start uniformly within one sample
  int oversampling = 8;                      ///< fine-grid factor before the anti-alias FIR
  std::vector<DoubleHit> double_hits;
  std::vector<Clipping> clipping;
  /// Several hammer force levels (N): impacts_per_reference impacts at each level, numbered on
  /// from one level to the next (level 1: 1..n, level 2: n+1..2n, ...), each peak spread by
  /// force_spread. Empty: one level, force_peak_n.
  std::vector<double> force_levels_n;
  std::uint64_t seed = 1;
  /// true: impact numbers continue across sets in SimulateHammerTest (one flat record list can
  /// then hold several sets unambiguously); SimulateHammerTestSets always numbers 1..n per set.
  bool number_impacts_across_sets = true;
};

/// The hammer pulse must span at least this many steps of the simulator's fine time grid. A pulse
/// shorter than one step can fall between two fine samples and its force be lost (all-zero
/// records); the sampled half-sine's impulse is off by up to 0.82/N² at N steps (5 % at 4, 0.3 %
/// at 16: the default 8× grid gives a 1 ms pulse at 2048 Hz 16 steps, and such plans are unchanged).
inline constexpr int kFineStepsPerPulse = 16;
/// The finest grid the simulator makes (memory and FIR length grow with it).
inline constexpr int kMaxOversampling = 256;

/// The fine-grid factor a simulation uses: `oversampling`, raised until the pulse spans
/// kFineStepsPerPulse fine steps. Throws std::invalid_argument when that needs more than
/// kMaxOversampling (ShortestSimulatedPulse says the limit).
int EffectiveOversampling(double pulse_duration_s, double sample_rate_hz, int oversampling);

/// The shortest hammer pulse the simulator resolves at `sample_rate_hz`, s.
double ShortestSimulatedPulse(double sample_rate_hz);

/// Records of one roving set, as one acquisition file would hold them.
struct SimulatedSet {
  std::vector<TimeRecord> records;
};

/// One SimulatedSet per roving set. Per impact: a force record (channel = reference, quantity 13,
/// unit "N") then one record per response DOF; impact numbers 1..impacts_per_reference per point.
/// truth_per_set.size() == 1: the same structure for every set; otherwise one per roving set.
std::vector<SimulatedSet> SimulateHammerTestSets(const std::vector<ModalTruth>& truth_per_set,
                                                 const HammerTestPlan& plan);

/// All sets in one list (impact numbers continue across sets unless
/// plan.number_impacts_across_sets is false).
std::vector<TimeRecord> SimulateHammerTest(const std::vector<ModalTruth>& truth_per_set, const HammerTestPlan& plan);

/// Low-level: the noise-free DAQ-sampled force and responses of one impact (force at `ref`,
/// pulses given as (start time s, peak N)), exposed for tests of the superposition identities.
/// The fine grid is EffectiveOversampling(pulse_duration_s, sample_rate_hz, oversampling).
struct ImpactSignals {
  std::vector<double> force;
  std::vector<std::vector<double>> responses;  ///< per response DOF
};
ImpactSignals SimulateImpact(const ModalTruth& truth, const Dof& ref, const std::vector<Dof>& responses,
                             const std::vector<std::pair<double, double>>& pulses, double pulse_duration_s,
                             double sample_rate_hz, int samples, Quantity quantity, int oversampling = 8);

/// Simulates one noise-free impact: hammer DOF, response DOFs, pulses (start time s, peak N).
using ImpactFunction = std::function<ImpactSignals(const Dof& ref, const std::vector<Dof>& responses,
                                                   const std::vector<std::pair<double, double>>& pulses)>;

/// As SimulateHammerTestSets / SimulateHammerTest (noise, double hits, clipping, force levels,
/// numbering), with each impact simulated by `impact_per_set` (one function, or one per roving
/// set): e.g. SimulateImpactInTime for structures with non-linear elements.
std::vector<SimulatedSet> SimulateHammerTestSetsWith(const std::vector<ImpactFunction>& impact_per_set,
                                                     const HammerTestPlan& plan);
std::vector<TimeRecord> SimulateHammerTestWith(const std::vector<ImpactFunction>& impact_per_set,
                                               const HammerTestPlan& plan);

}  // namespace ema::acquisition
