// The spatial model of a test article as plain value types (model-format.md). No file I/O here:
// ema/formats/model_file.hpp reads and writes these from/to the TOML model file.
//
// Units are SI throughout (m, kg, N, s, Pa, rad). Forces of interface laws are positive in
// compression; a law's deflection d is its compression.
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <compare>
#include <iosfwd>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <type_traits>
#include <variant>
#include <vector>

namespace ema::model {

/// Reserved body name: fixed, no DOF.
inline constexpr const char* kGround = "ground";

struct Law;

/// F = k d.
struct LinearLaw {
  double k = 0.0;  ///< N/m (N m/rad for rotational springs)
};

/// Monotone force-deflection table, interpolated with a monotone cubic (Fritsch-Carlson).
/// The operating point is given by deflection or by force (exactly one; deflection wins).
struct TableLaw {
  std::vector<double> deflection;  ///< strictly increasing
  std::vector<double> force;       ///< strictly increasing with deflection
  std::optional<double> operating_deflection;
  std::optional<double> operating_force;
};

/// Air-film load-lift curve W(h): load decreasing with gap. Stiffness is -dW/dh at the gap.
struct AirFilmLaw {
  std::vector<double> gap;   ///< strictly increasing, m
  std::vector<double> load;  ///< strictly decreasing, N
  double operating_gap = 0.0;  ///< used when the law stands alone (not inside a chain)
};

/// Hertz contact F = 4/3 E' sqrt(R') (d - offset)^1.5, k = 2 E' sqrt(R' (d - offset)).
/// Operating point: compression `deflection` or `force` (preload); inside a chain the chain's
/// force sets it.
struct HertzLaw {
  double modulus = 0.0;  ///< effective modulus E', Pa
  double radius = 0.0;   ///< effective radius R', m
  double offset = 0.0;   ///< free play before contact, m
  std::optional<double> operating_deflection;
  std::optional<double> operating_force;
};

/// A chain of elements carrying one force. With an air film in the chain, the operating point is
/// solved from `setting`: W(h) = F_i(d_i) for all i and h = setting + sum d_i. Without an air
/// film the chain carries `force` (default 0: each element at zero load, or at its own operating
/// point when that is given).
struct SeriesLaw {
  std::vector<Law> elements;
  double setting = 0.0;           ///< m, lift measured at the outer end of the chain
  std::optional<double> force;    ///< N, chain force when there is no air film
};

/// Micro-slip joint (a bolted or clamped interface loaded along its slip direction): a Jenkins
/// element, a spring of stiffness k in series with a Coulomb slider that slips at slip_force,
/// or with `elements` > 1 an Iwan element: that many Jenkins elements in parallel, each of
/// stiffness k/elements, whose slip displacements are spread evenly up to u_max so that their
/// slip forces sum to slip_force (the macro-slip force). Below the first slip the joint is
/// stuck and linear with stiffness k: the eigen-solution uses k. It is hysteretic, so only a
/// time integration (ema simulate with integration = "time") sees the slip: the frequency falls
/// and the damping rises with the amplitude. See docs/model.md.
struct MicroSlipLaw {
  double k = 0.0;           ///< stuck stiffness, N/m (N m/rad rotational)
  double slip_force = 0.0;  ///< N (N m): force at which the joint slips as a whole (macro-slip)
  int elements = 1;         ///< 1 = Jenkins; > 1 = Iwan with that many parallel Jenkins elements
};

/// One interface law (the variant of every law kind of model-format.md).
struct Law {
  std::variant<LinearLaw, TableLaw, AirFilmLaw, HertzLaw, SeriesLaw, MicroSlipLaw> value;

  Law() = default;
  template <typename T>
    requires(!std::is_same_v<std::decay_t<T>, Law>)
  Law(T law) : value(std::move(law)) {}  // NOLINT: implicit on purpose (Law l = LinearLaw{k})

  /// "linear", "table", "air_film", "hertz", "series", "micro_slip".
  std::string KindName() const;
  /// True for every law whose stiffness depends on an operating point (all but linear and
  /// micro_slip, and a series chain only when one of its elements is non-linear).
  bool IsNonlinear() const;
  /// True when the force is not a linear function of the deflection in time (every law but
  /// linear; a series chain when one of its elements is): what ema simulate integrates.
  bool IsNonlinearInTime() const;
};

/// Rigid body, 6 DOF (ux uy uz rx ry rz) at its centre of mass.
struct Body {
  std::string name;
  double mass = 0.0;                                  ///< kg
  Eigen::Vector3d inertia = Eigen::Vector3d::Zero();  ///< Ixx Iyy Izz about the centre, kg m^2
  /// Products of inertia Ixy Iyz Ixz = integral of x y dm etc.; the inertia tensor holds -Ixy.
  Eigen::Vector3d products = Eigen::Vector3d::Zero();
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();   ///< m, global
  int line = 0;                                       ///< source line, 0 if built in code
  /// Relative 1σ of mass and inertia (model-format.md "Prior knowledge"); NaN: not given.
  double uncertainty = std::numeric_limits<double>::quiet_NaN();
};

/// Where a spring end, point mass or test point sits: on a body at a global position, or at an
/// FE node (node > 0).
struct Anchor {
  std::string body;                               ///< body name ("ground" allowed); empty for FE node
  int node = 0;                                   ///< FE node id, > 0 when anchored to a node
  Eigen::Vector3d at = Eigen::Vector3d::Zero();   ///< m, global position (bodies)
  bool has_at = false;                            ///< false: at defaults (body centre / end a)

  bool IsNode() const { return node > 0; }
  bool IsGround() const { return node <= 0 && body == kGround; }
};

/// Point mass fixed to a body or an FE node (a sensor, a payload).
struct PointMass {
  std::string name;
  Anchor where;
  double mass = 0.0;  ///< kg
  int line = 0;
};

/// Spring between end a and end b along (translational) or about (rotational) `direction`.
struct Spring {
  enum class Kind { kTranslational, kRotational };
  std::string name;
  std::string group;  ///< physical kind of interface; diagnosis works on groups
  Kind kind = Kind::kTranslational;
  Anchor a;
  Anchor b;           ///< b.at defaults to a.at
  Eigen::Vector3d direction = Eigen::Vector3d::UnitZ();  ///< normalised when solved
  Law law;
  double stiffness_factor = 1.0;  ///< multiplies the linearised stiffness (stiffness_scale effect)
  int line = 0;
  /// One joint, bolt, pad or mount of the group (model-format.md "Members"); empty: derived from
  /// the spring ends (see MemberNames in effects.hpp).
  std::string member;
  /// Relative 1σ of the stiffness, as 1σ of ln(factor) (model-format.md "Prior knowledge"); NaN: not given.
  double uncertainty = std::numeric_limits<double>::quiet_NaN();
};

/// Modal damping: one ratio for every mode, or per elastic mode in frequency order (the last
/// value repeats for modes beyond the list).
struct Damping {
  double ratio = 0.0;
  std::vector<double> ratios;
  double RatioOfMode(int elastic_mode_index) const;
};

/// A test point: ties a UFF node id of a test to a place on the model.
struct TestPoint {
  int id = 0;
  Anchor where;
  int line = 0;
};

/// One test configuration: operating values by spring group (series: setting; air_film: gap;
/// table/hertz: deflection, or force when the law's operating point is a force).
struct Setup {
  std::string name;
  std::map<std::string, double> operating;
  int line = 0;
};

/// The kinds of effect of the vocabulary (model-format.md "Effects"), in its order. Their names
/// ("series_compliance", ...) live once, in model::EffectKindTable (effects.hpp): text is parsed
/// into a kind where it enters (model file, DIAG.json) and printed through that table.
enum class EffectKind { kSeriesCompliance, kStiffnessScale, kOperatingPoint, kAddedMass, kMassScale, kGroundSpring };
/// A kind goes into JSON by its name, never as its number: nlohmann::json, which would otherwise
/// write an enum's integer without a word, finds this deleted overload (by argument-dependent lookup).
template <typename Json>
void to_json(Json& json, EffectKind kind) = delete;

/// What an effect acts on (model-format.md "Effects"), typed. Its text is read once, where text
/// enters (model::ParseEffectTarget, effects.hpp: the model file's [[effect]] reader, which
/// DIAG.json's effects go through too), and written once (TargetText: model files, JSON, reports,
/// Describe); everything in between compares these values. The text gives the form; the model
/// says what a name is — spring groups, FE part groups, parts in no group and bodies share one
/// namespace (model-format.md) — through TargetSprings, TargetParts, TargetBody and TargetPoints.
struct EffectTarget {
  enum class Form {
    kName,         ///< "joints", "top", "clamp": a spring group, an FE part group, a part in no group or a body
    kMember,       ///< "joints/J3": one member of a spring group, or one part of an FE part group
    kEveryMember,  ///< "joints/*": any one member of a group; a sum over members, no effect's
    kAllPoints,    ///< "all_points": every test point
    kPoints,       ///< "points:101,102": the test points of these ids
    kEveryPoint,   ///< "points:*": any single test point; a sum over points, no effect's
  };
  Form form = Form::kName;
  std::string name;         ///< kName: the name; kMember, kEveryMember: the group's name
  std::string member;       ///< kMember: the member's name (may hold '/': an implicit member named after its springs)
  std::vector<int> points;  ///< kPoints: the test point ids, in the order given

  static EffectTarget Named(std::string name);
  static EffectTarget MemberOf(std::string group, std::string member);
  static EffectTarget EveryMemberOf(std::string group);
  static EffectTarget AllPoints();
  static EffectTarget Points(std::vector<int> ids);
  static EffectTarget EveryPoint();

  bool IsPoints() const { return form == Form::kAllPoints || form == Form::kPoints; }
  friend bool operator==(const EffectTarget&, const EffectTarget&) = default;
  /// An order for maps and sets (by form, then names, then ids); not the order of the texts.
  friend auto operator<=>(const EffectTarget&, const EffectTarget&) = default;
};

/// The text of a target, as model files, JSON and reports write it and ParseEffectTarget reads it:
/// "joints", "joints/J3", "joints/*", "all_points", "points:101,102", "points:*" (the one printer).
std::string TargetText(const EffectTarget& target);
/// Its text on a stream (TargetText), for messages and test output.
std::ostream& operator<<(std::ostream& out, const EffectTarget& target);
/// A target goes into JSON as its text, written by TargetText where it is put there; this deleted
/// overload (found by argument-dependent lookup) keeps nlohmann::json from guessing another way.
template <typename Json>
void to_json(Json& json, const EffectTarget& target) = delete;

/// An effect of the vocabulary (model-format.md): kind, target, parameters and optional law.
struct Effect {
  EffectKind kind = EffectKind::kSeriesCompliance;  ///< always set by whoever makes the effect
  EffectTarget target;
  std::map<std::string, double> parameters;  ///< factor, value, mass, k (per kind)
  /// series_compliance: the law in series. Without a law, parameters["k"] means a linear law
  /// (handy for fitting); WriteModelWithEffects then writes it as law = { linear = { k } }.
  std::optional<Law> law;
  int line = 0;
};

/// One part of an FE model (model-format.md "FE models built from parts"): the part's own
/// contribution to the global stiffness (and mass), in the [fe] DOF order — a bolted-joint zone,
/// a deck panel, a support. K = [fe].stiffness + Σ factor·part.stiffness, likewise M.
struct FePart {
  std::string name;                        ///< unique among parts
  std::string group;                       ///< "" = a part in no group; else the group's member `name`
  /// n × n (full storage), or null for none. Shared and never modified: copies of a model (one per
  /// effect tried by the diagnosis) share the part matrices; effects change only the factors.
  std::shared_ptr<const Eigen::SparseMatrix<double>> stiffness;
  std::shared_ptr<const Eigen::SparseMatrix<double>> mass;
  double stiffness_factor = 1.0;           ///< multiplies the stiffness (stiffness_scale effect)
  double mass_factor = 1.0;                ///< multiplies the mass (mass_scale effect)
  /// Relative 1σ of the stiffness, as 1σ of ln(factor) (model-format.md "Prior knowledge"); NaN: not given.
  double uncertainty = std::numeric_limits<double>::quiet_NaN();
  int line = 0;                            ///< source line of the [[fe.part]] block
  std::string stiffness_file, mass_file;   ///< the matrices' files, for messages

  bool HasMass() const { return mass != nullptr; }
  bool HasStiffness() const { return stiffness != nullptr; }
  /// How an effect names it: "GROUP/NAME" for a member of a group, "NAME" for a part in no group.
  EffectTarget Target() const {
    return group.empty() ? EffectTarget::Named(name) : EffectTarget::MemberOf(group, name);
  }
};

/// Imported finite-element matrices (symmetric; lower or full storage accepted). `mass` and
/// `stiffness` may be 0 × 0 (none) when parts carry the rest; the size is the DOF map's.
struct FeMatrices {
  Eigen::SparseMatrix<double> mass;
  Eigen::SparseMatrix<double> stiffness;
  struct DofEntry {
    int node = 0;
    int dof = 0;  ///< 1..6 = ux uy uz rx ry rz
  };
  std::vector<DofEntry> dofs;                      ///< one per matrix row
  std::map<int, Eigen::Vector3d> node_positions;   ///< node id -> global position, m
  std::vector<FePart> parts;                       ///< [[fe.part]] blocks, in file order
  std::string origin;                              ///< file names, for messages
  std::string mass_file, stiffness_file;           ///< the matrices' files, for messages naming an entry

  bool Empty() const { return dofs.empty(); }
  int Size() const { return static_cast<int>(dofs.size()); }
};

/// A part's matrix is a sum of element matrices, each positive semi-definite: an LDLᵀ of its
/// non-zero rows, shifted by 1e-9 of its largest diagonal entry, then has no negative pivot
/// (Sylvester's law of inertia). Returns the matrix row of the first non-positive pivot, or -1
/// when there is none (also for a matrix without non-zero rows). The model file's reader and the
/// Python binding name the DOF of that row in their own words.
int FirstNegativePivotRow(const Eigen::SparseMatrix<double>& a);

/// The whole spatial model.
struct Model {
  std::string name;
  std::vector<Body> bodies;
  std::vector<PointMass> masses;
  std::vector<Spring> springs;
  Damping damping;
  std::vector<TestPoint> points;
  std::vector<Setup> setups;
  /// Effects not yet applied. ApplyEffects() applies and clears them; Solve() applies any that
  /// are still pending, so a model read from a file is always solved with its [[effect]] blocks.
  std::vector<Effect> effects;
  FeMatrices fe;
  /// [priors]: default prior 1σ per effect kind where an item has no `uncertainty`
  /// (model-format.md "Prior knowledge").
  std::map<EffectKind, double> priors;
  /// [priors] stiffness_fault_share / stiffness_fault_width (model-format.md, added turn 4): the
  /// fault tail of a stiffness factor's prior, overriding DiagnoseOptions' defaults when given.
  std::optional<double> stiffness_fault_share, stiffness_fault_width;
  std::string origin;  ///< model file path, for messages

  const Body* FindBody(const std::string& name) const;
  Body* FindBody(const std::string& name);
  /// "file:line" of an element for error messages ("file" when line is 0).
  std::string Where(int line) const;
};

}  // namespace ema::model
