// Typed results from fuzzer bytes, for the JSON writer targets (json_results_fuzz.cpp,
// json_modes_roundtrip_fuzz.cpp; docs/reliability.md). Texts are arbitrary bytes (NUL, Latin-1,
// broken and overlong UTF-8); doubles are NaN, ±Inf, denormals, ±max, ±0 or any bit pattern; sets
// are empty, small or large (bounded so that one input stays cheap). The structs keep only the
// invariants their producers guarantee and the writers rely on (a mode's shape has one value per
// DOF; indices point into their sets); every size a writer checks for itself may mismatch.
#pragma once

#include <fuzzer/FuzzedDataProvider.h>

#include <algorithm>
#include <bit>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "ema/core/types.hpp"

namespace ema::fuzz {

class Gen {
 public:
  Gen(const std::uint8_t* data, std::size_t size) : p_(data, size) {}

  FuzzedDataProvider& provider() { return p_; }
  bool Bool() { return p_.ConsumeBool(); }
  /// A set size: mostly 0..3 (sets nest: cheap inputs keep the campaign at thousands per second), one time
  /// in 32 anything up to `max` (the large sets); 0 once the input is used up.
  std::size_t Count(std::size_t max) {
    const auto pick = p_.ConsumeIntegral<std::uint8_t>();
    if (pick < 248) return std::min<std::size_t>(pick % 4, max);
    return p_.ConsumeIntegralInRange<std::size_t>(0, max);
  }
  int Int(int lo, int hi) { return p_.ConsumeIntegralInRange<int>(lo, hi); }
  int AnyInt() { return p_.ConsumeIntegral<int>(); }

  double Double() {
    switch (p_.ConsumeIntegralInRange<int>(0, 15)) {
      case 0: return std::numeric_limits<double>::quiet_NaN();
      case 1: return std::numeric_limits<double>::infinity();
      case 2: return -std::numeric_limits<double>::infinity();
      case 3: return std::numeric_limits<double>::denorm_min();
      case 4: return std::numeric_limits<double>::max();
      case 5: return std::numeric_limits<double>::lowest();
      case 6: return 0.0;
      case 7: return -0.0;
      case 8: return -std::numeric_limits<double>::quiet_NaN();
      case 9: return std::bit_cast<double>(p_.ConsumeIntegral<std::uint64_t>());  // any pattern, signalling NaNs too
      case 10: return static_cast<double>(p_.ConsumeIntegral<std::int32_t>()) / 1024.0;
      default: return p_.ConsumeFloatingPoint<double>();
    }
  }
  std::complex<double> Complex() {
    const double re = Double();
    return {re, Double()};
  }

  /// Arbitrary bytes; sometimes one of a few crafted ones.
  std::string Text() {
    switch (p_.ConsumeIntegralInRange<int>(0, 7)) {
      case 0: return "m/s\xB2";                  // Latin-1 ²
      case 1: return std::string("a\0b", 3);     // NUL
      case 2: return "\xC0\x80\xED\xA0\x80\xF4\x90\x80\x80";  // overlong NUL, a surrogate, > U+10FFFF
      case 3: return "\xE2\x82";                 // cut multi-byte sequence
      default: return p_.ConsumeRandomLengthString(48);
    }
  }
  std::vector<std::string> Texts(std::size_t max) {
    std::vector<std::string> out(Count(max));
    for (auto& s : out) s = Text();
    return out;
  }
  std::vector<double> Doubles(std::size_t max) {
    std::vector<double> out(Count(max));
    for (auto& v : out) v = Double();
    return out;
  }
  Eigen::VectorXd Vector(std::size_t n) {
    Eigen::VectorXd v(static_cast<Eigen::Index>(n));
    for (Eigen::Index i = 0; i < v.size(); ++i) v[i] = Double();
    return v;
  }
  Eigen::VectorXcd ComplexVector(std::size_t n) {
    Eigen::VectorXcd v(static_cast<Eigen::Index>(n));
    for (Eigen::Index i = 0; i < v.size(); ++i) v[i] = Complex();
    return v;
  }

  /// Direction codes mostly within ±8 (the named ones, scalar 0 and unknown codes), sometimes any
  /// int (INT_MIN included: DirectionName once negated it); any node id.
  Dof AnyDof() {
    const int node = AnyInt();
    return {node, Int(0, 15) == 0 ? AnyInt() : Int(-8, 8)};
  }
  std::vector<Dof> Dofs(std::size_t max) {
    std::vector<Dof> out(Count(max));
    for (auto& d : out) d = AnyDof();
    return out;
  }

  /// A mode set: `max_dofs` DOFs at most, at most `max_values` shape values in all.
  ModeSet Modes(std::size_t max_dofs, std::size_t max_modes, std::size_t max_values) {
    ModeSet set;
    set.dofs = Dofs(max_dofs);
    const std::size_t n = set.dofs.size();
    const std::size_t modes = Count(std::min(max_modes, max_values / std::max<std::size_t>(n, 1)));
    set.modes.resize(modes);
    for (Mode& m : set.modes) FillMode(&m, n);
    set.source = Text();
    return set;
  }

  void FillMode(Mode* m, std::size_t dofs) {
    m->frequency_hz = Double();
    m->damping_ratio = Double();
    m->pole = Complex();
    m->shape = ComplexVector(dofs);
    m->participation = ComplexVector(Count(4));
    m->mpc = Double();
    m->mpd = Double();
    m->mcf = Double();
    m->frequency_spread_hz = Double();
    m->damping_spread = Double();
    m->frequency_std_hz = Double();
    m->damping_ratio_std = Double();
    // The writer checks this size itself: any size.
    if (Bool()) m->shape_std = Vector(Bool() ? dofs : Count(dofs + 2));
    m->unit_modal_mass = Bool();
    if (Bool()) {
      m->set_frequency_hz = Doubles(6);
      m->set_damping_ratio = Doubles(6);  // sizes may differ: the writer checks them
      m->set_frequency_std_hz = Doubles(6);
    }
  }

 private:
  FuzzedDataProvider p_;
};

}  // namespace ema::fuzz
