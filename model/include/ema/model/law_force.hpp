// The force of an interface law in time, about its operating point: what `ema simulate`
// integrates when the plan asks for a time integration (docs/model.md "Laws in time").
//
// Sign: c is the change of the law's compression from the operating point (a spring's ends
// closing along `direction`, end a moving against it relative to end b, compresses it); the
// force change is compression positive, F(c) = F(d0 + c) - F(d0). Hysteretic laws (micro_slip)
// carry a state: Force() evaluates a trial compression from the committed state, Commit()
// accepts it at the end of a time step.
#pragma once

#include <string>
#include <vector>

#include "ema/model/model.hpp"
#include "ema/model/laws.hpp"

namespace ema::model {

class LawForce {
 public:
  /// `operating`: LinearizeLaw of the same law (with the setup's override applied).
  /// `range_m`: the largest compression change expected; chain laws are tabulated over
  /// ±range_m and extrapolated linearly beyond. `factor` scales the force (stiffness_scale).
  /// Throws InputError (with `where`) for laws it cannot evaluate.
  LawForce(const Law& law, const SpringState& operating, double range_m, double factor, const std::string& where);

  /// Force change at compression change c, from the committed state (no state change).
  double Force(double c) const;
  /// Accepts c as the state at the end of a time step (hysteretic laws).
  void Commit(double c);
  /// Back to the operating point at rest (stuck, no force change).
  void Reset();
  /// Linearised stiffness at the operating point (times factor): the part of the force that the
  /// assembled stiffness matrix already holds.
  double Stiffness() const { return stiffness_; }

 private:
  enum class Kind { kLinear, kCurve, kHertz, kMicroSlip };
  Kind kind_ = Kind::kLinear;
  double factor_ = 1.0;
  double stiffness_ = 0.0;
  // kCurve: F(c) by monotone interpolation of (c, F) samples, linear beyond.
  std::vector<double> c_, f_, slope_;
  // kHertz: c_h (4/3 E' sqrt(R')) and the penetration at the operating point.
  double hertz_c_ = 0.0, pen0_ = 0.0, f0_ = 0.0;
  // kMicroSlip: per Jenkins element its stiffness and slip force; committed state.
  std::vector<double> k_i_, fs_i_, f_committed_;
  double c_committed_ = 0.0;
};

}  // namespace ema::model
