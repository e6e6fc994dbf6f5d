// Vocabulary types shared by every ema module. Plain value types, no I/O.
//
// Conventions (see docs/conventions.md and shared spec algorithms.md §0):
//  * time dependence e^{+jwt}; DFT X_k = sum x_n e^{-j 2 pi k n / N} (the FFTW sign);
//  * poles lambda = -zeta*w + j*w*sqrt(1-zeta^2) in rad/s, Im > 0 for the stored member of a pair;
//  * directions use the UFF direction codes: 1,2,3 = +X,+Y,+Z; 4,5,6 = +RX,+RY,+RZ;
//    negative = the opposite sense; 0 = scalar (no direction).
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

namespace ema {

inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
inline constexpr double kTwoPi = 6.283185307179586476925286766559;

/// A measurement degree of freedom: a node id and a signed UFF direction code.
struct Dof {
  int node = 0;
  int direction = 0;  ///< UFF code: ±1..±3 translations X,Y,Z; ±4..±6 rotations; 0 scalar

  friend bool operator==(const Dof&, const Dof&) = default;
  friend auto operator<=>(const Dof&, const Dof&) = default;
};

/// Axis names of the UFF direction codes 1..6 (entry code - 1): the program's one axis table.
inline constexpr std::string_view kAxisNames[] = {"X", "Y", "Z", "RX", "RY", "RZ"};

/// The unsigned UFF direction code (1..6) of an axis name "X".."RZ", case-insensitive; 0 if unknown.
inline int AxisCode(std::string_view axis) {
  for (int i = 0; i < 6; ++i) {
    const std::string_view name = kAxisNames[i];
    if (axis.size() != name.size()) continue;
    bool same = true;
    for (size_t k = 0; k < name.size() && same; ++k) {
      const char c = axis[k];
      same = (c >= 'a' && c <= 'z' ? static_cast<char>(c - 'a' + 'A') : c) == name[k];
    }
    if (same) return i + 1;
  }
  return 0;
}

/// "+X", "-Z", "+RY", "S" (scalar) for a UFF direction code.
inline std::string DirectionName(int code) {
  // Built by appending: GCC 12 warns falsely (-Wrestrict) on `"literal" + std::string` when inlined.
  std::string name;
  if (code == 0) return name.assign("S");
  // Out of the named range first: negating INT_MIN would overflow.
  if (code > 6 || code < -6) return name.append("?").append(std::to_string(code));
  const int a = code < 0 ? -code : code;
  return name.append(code < 0 ? "-" : "+").append(kAxisNames[a - 1]);
}

/// Parses "+X", "X", "-z", "+RY" (case-insensitive) into a UFF direction code; 0 if unknown.
inline int ParseDirection(std::string_view text) {
  int sign = 1;
  if (!text.empty() && (text.front() == '+' || text.front() == '-')) {
    sign = text.front() == '-' ? -1 : 1;
    text.remove_prefix(1);
  }
  return sign * AxisCode(text);
}

inline std::string DofName(const Dof& dof) { return std::to_string(dof.node).append(DirectionName(dof.direction)); }

/// Physical quantity of a channel. Values are the UFF 58 "specific data type" codes.
enum class Quantity : int {
  kUnknown = 0,
  kDisplacement = 8,
  kVelocity = 11,
  kAcceleration = 12,
  kForce = 13,
};

/// Kind of FRF by its response quantity (pyEMA: frf_type).
enum class FrfType { kReceptance, kMobility, kAccelerance };

inline FrfType FrfTypeOf(Quantity response) {
  switch (response) {
    case Quantity::kDisplacement: return FrfType::kReceptance;
    case Quantity::kVelocity: return FrfType::kMobility;
    default: return FrfType::kAccelerance;
  }
}

/// One sampled channel of one impact, as acquired (a UFF 58 function-type-1 record or a CSV column).
struct TimeRecord {
  Dof channel;                 ///< where the sensor (or, for the force record, the hammer) is
  Dof reference;               ///< the hammer point of this impact
  int impact = 0;              ///< impact number within its point (UFF: load case id)
  Quantity quantity = Quantity::kUnknown;
  double sample_interval_s = 0.0;
  double start_time_s = 0.0;
  std::vector<double> samples;
  double full_scale = kNaN;    ///< ADC / channel range in the samples' unit, if known
  std::string unit;            ///< unit label as read, e.g. "N", "m/s^2", "g"
  std::string origin;          ///< "file.unv, dataset 58 #12 (line 345)" for error messages
};

/// FRFs of one test on a uniform frequency grid, with the reference(s) as columns of H.
/// Orientation: h[r] is n_lines × n_outputs, the FRFs from reference r to every output
/// (column-major Eigen favours per-FRF work along the frequency axis).
struct FrfSet {
  Eigen::VectorXd frequency_hz;        ///< n_lines, uniformly spaced
  std::vector<Dof> outputs;            ///< response DOFs (rows of H)
  std::vector<Dof> references;         ///< reference DOFs (columns of H)
  std::vector<Eigen::MatrixXcd> h;     ///< per reference: n_lines × n_outputs; NaN where not measured
  std::vector<Eigen::MatrixXd> coherence;  ///< same shape as h; empty when unknown
  Eigen::MatrixXi averages;            ///< n_references × n_outputs accepted impacts; empty if unknown
  Quantity output_quantity = Quantity::kAcceleration;  ///< accelerance by default
  double window_decay_rate = 0.0;      ///< 1/tau [1/s] of an exponential window the FRFs carry
  bool roving_hammer = false;          ///< rows measured by a moving hammer, fixed sensors (reciprocity)
  /// Per output: the roving set (0-based) it was measured in — the impacts of one file that share
  /// their response nodes; empty when unknown (a file from another tool). Roving sensors load the
  /// article where and while their set is measured (diagnosis, refinement).
  std::vector<int> output_sets;
  std::string force_unit = "N";
  std::string response_unit = "m/s^2";

  int LineCount() const { return static_cast<int>(frequency_hz.size()); }
  int OutputCount() const { return static_cast<int>(outputs.size()); }
  int ReferenceCount() const { return static_cast<int>(references.size()); }
  /// The response DOFs of each roving set (sets in order of their index, DOFs in output order);
  /// empty when the sets are unknown.
  std::vector<std::vector<Dof>> RovingSets() const {
    std::vector<std::vector<Dof>> sets;
    if (output_sets.empty() || output_sets.size() != outputs.size()) return sets;
    std::vector<int> ids(output_sets);
    std::sort(ids.begin(), ids.end());
    ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
    sets.resize(ids.size());
    for (std::size_t o = 0; o < outputs.size(); ++o)
      sets[static_cast<std::size_t>(std::lower_bound(ids.begin(), ids.end(), output_sets[o]) - ids.begin())].push_back(outputs[o]);
    return sets;
  }
  /// The nodes of each roving set (RovingSets, each node once, in order of first output).
  std::vector<std::vector<int>> RovingSetNodes() const {
    std::vector<std::vector<int>> nodes;
    for (const std::vector<Dof>& set : RovingSets()) {
      std::vector<int>& list = nodes.emplace_back();
      for (const Dof& d : set)
        if (std::find(list.begin(), list.end(), d.node) == list.end()) list.push_back(d.node);
    }
    return nodes;
  }
};

/// A node of the test or model geometry (global coordinates, metres).
struct Node {
  int id = 0;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
};

/// One mode: pole, shape at ModeSet::dofs, quality indicators.
struct Mode {
  double frequency_hz = 0.0;           ///< undamped natural frequency |lambda|/2pi
  double damping_ratio = 0.0;          ///< -Re(lambda)/|lambda|
  std::complex<double> pole{0.0, 0.0}; ///< rad/s, Im > 0
  Eigen::VectorXcd shape;              ///< aligned with ModeSet::dofs
  Eigen::VectorXcd participation;      ///< per reference (empty for model modes)
  double mpc = kNaN;                   ///< modal phase collinearity, 0..1
  double mpd = kNaN;                   ///< mean phase deviation, degrees
  double mcf = kNaN;                   ///< mode complexity factor 1 - MPC(eigen form), 0 = real mode
  double frequency_spread_hz = kNaN;   ///< std. dev. of the stable-pole cluster
  double damping_spread = kNaN;        ///< std. dev. of the cluster's damping ratio
  double frequency_std_hz = kNaN;      ///< 1 sigma of frequency_hz from the data's noise (ML refinement)
  double damping_ratio_std = kNaN;     ///< 1 sigma of damping_ratio
  Eigen::VectorXd shape_std;           ///< 1 sigma of |shape| per DOF (empty when unknown)
  bool unit_modal_mass = false;        ///< shape scaled to unit modal mass
  /// Roving-sensor tests: the mode as each roving set saw it (its sensors load the article while
  /// it is measured), in the order of the sets; frequency_hz is then their mean. Empty otherwise.
  std::vector<double> set_frequency_hz, set_damping_ratio, set_frequency_std_hz;
};

/// A set of modes with the DOFs their shapes are given at.
struct ModeSet {
  std::vector<Dof> dofs;
  std::vector<Mode> modes;
  std::vector<Node> geometry;          ///< test/model geometry when known (may be empty)
  std::string source;                  ///< where the set came from, for messages and reports
  /// Set by readers when the geometry's length unit was not stated (a UFF file without dataset
  /// 164): the coordinates were taken as metres. Outputs that use positions repeat it.
  std::string geometry_units_note;
};

/// Pole (rad/s) to undamped natural frequency (Hz) and damping ratio.
inline void PoleToFrequencyAndDamping(std::complex<double> pole, double* frequency_hz, double* damping_ratio) {
  const double w = std::abs(pole);
  *frequency_hz = w / kTwoPi;
  *damping_ratio = w > 0.0 ? -pole.real() / w : 0.0;
}

/// Natural frequency (Hz) and damping ratio to the pole with Im > 0 (rad/s).
inline std::complex<double> FrequencyAndDampingToPole(double frequency_hz, double damping_ratio) {
  const double w = kTwoPi * frequency_hz;
  return {-damping_ratio * w, w * std::sqrt(std::max(0.0, 1.0 - damping_ratio * damping_ratio))};
}

}  // namespace ema
