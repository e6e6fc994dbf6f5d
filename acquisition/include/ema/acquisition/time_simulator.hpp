// Hammer impacts on a structure with non-linear interface elements, integrated in time
// (Newmark average acceleration, fixed-point iterations on the non-linear forces), sampled like
// the modal simulator (fine grid, the same anti-alias FIR on every channel, decimation). With
// no non-linear element it reproduces the modal superposition of simulator.hpp to the
// integrator's period error (docs/model.md "Laws in time").
#pragma once

#include <Eigen/Core>
#include <functional>
#include <memory>
#include <vector>

#include "ema/acquisition/simulator.hpp"
#include "ema/core/types.hpp"

namespace ema::acquisition {

/// The force of one non-linear element as a function of its compression change c from the
/// operating point (compression positive, force change positive in compression). Hysteretic
/// elements keep a state: Force() evaluates a trial c from the committed state, Commit()
/// accepts it at the end of each time step, Reset() returns to rest before each impact.
class RestoringForce {
 public:
  virtual ~RestoringForce() = default;
  virtual double Force(double c) const = 0;
  virtual void Commit(double c) = 0;
  virtual void Reset() = 0;
  /// The linear part k c already held by the stiffness matrix (the integrator adds only
  /// Force(c) - k c).
  virtual double Stiffness() const = 0;
};

/// One non-linear element: c = coefficients · x (x: the system's DOFs), and it acts on the DOFs
/// with coefficients × force (the virtual work of a compression force).
struct NonlinearElement {
  Eigen::VectorXd coefficients;
  std::shared_ptr<RestoringForce> force;
};

/// A structure for the time integrator: M and K over n DOFs (K holds every element's linear
/// stiffness k), the modal damping of its elastic modes, the test DOFs as rows of an
/// observation matrix (displacement along each test DOF), and the non-linear elements.
struct TimeDomainTruth {
  Eigen::MatrixXd mass, stiffness;   ///< n × n, symmetric, M positive definite
  /// Damping ratio of each elastic mode of (K, M) in frequency order; the last value repeats.
  /// Rigid-body modes (ω ≈ 0) are undamped.
  std::vector<double> damping_ratios;
  std::vector<Dof> dofs;             ///< test DOFs (hammer points and sensors)
  Eigen::MatrixXd observation;       ///< dofs.size() × n
  std::vector<NonlinearElement> elements;
};

/// Integrates impacts on one TimeDomainTruth in modal coordinates of the linearised system
/// (every mode kept, so nothing is truncated): Newmark average acceleration per mode (no
/// numerical damping; period error (ω Δt)²/12), the non-linear element forces coupled in by
/// fixed-point iterations on the elements' compressions at every step.
class TimeIntegrator {
 public:
  /// Solves the eigenproblem once. Throws std::invalid_argument for inconsistent sizes or a mass
  /// matrix that is not positive definite.
  explicit TimeIntegrator(TimeDomainTruth truth);

  /// The noise-free, DAQ-sampled force and responses of one impact at `ref` (pulses: start
  /// time s, peak N), steps of 1/(sample_rate_hz × oversampling). Elements are reset first.
  /// Throws ema::ConvergenceError when the iterations do not converge (time step too coarse for
  /// an element's tangent stiffness: raise the oversampling).
  ImpactSignals Simulate(const Dof& ref, const std::vector<Dof>& responses,
                         const std::vector<std::pair<double, double>>& pulses, double pulse_duration_s,
                         double sample_rate_hz, int samples, Quantity quantity, int oversampling = 8);

  /// Natural frequencies (Hz) of the linearised system, rigid-body modes included (0).
  const std::vector<double>& FrequenciesHz() const { return frequency_hz_; }

 private:
  int IndexOf(const Dof& dof) const;
  TimeDomainTruth truth_;
  Eigen::MatrixXd phi_;          ///< n × n mass-normalised modes
  Eigen::VectorXd omega_, zeta_; ///< per mode
  Eigen::MatrixXd element_modal_;  ///< elements × modes: coefficients^T phi
  Eigen::MatrixXd output_modal_;   ///< test DOFs × modes: observation phi
  std::vector<double> frequency_hz_;
};

}  // namespace ema::acquisition
