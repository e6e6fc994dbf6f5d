// Assembly of M and K at the operating point and the generalised eigenproblem K phi = w^2 M phi.
#include "ema/model/solve.hpp"
#include "assembly.hpp"
#include "block_lanczos.hpp"
#include "sparse_factor.hpp"

#include <Eigen/Dense>
#include <Eigen/SparseCholesky>
#include <Spectra/SymGEigsShiftSolver.h>
#include <Spectra/MatOp/SparseSymMatProd.h>
#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <set>
#include <iomanip>
#include <sstream>

#include "ema/core/error.hpp"
#include "ema/model/effects.hpp"

namespace ema::model {
// The DOF index is named (not in the anonymous namespace) because detail::RestAssembler keeps one.
namespace assembly {

using Coeffs = std::vector<std::pair<int, double>>;
using Triplets = std::vector<Eigen::Triplet<double>>;

// (node, dof 1..6) -> system index of the [fe] DOF map: one sorted array, not a node per DOF —
// the diagnosis assembles a model once per candidate evaluation, thousands of times.
struct FeDofIndex {
  std::vector<std::pair<std::pair<int, int>, int>> sorted;
  /// The system index, or -1 when the map has no such DOF.
  int Find(int node, int dof) const {
    const std::pair<int, int> key{node, dof};
    auto it = std::lower_bound(sorted.begin(), sorted.end(), key,
                               [](const auto& entry, const std::pair<int, int>& k) { return entry.first < k; });
    return it != sorted.end() && it->first == key ? it->second : -1;
  }
};

struct DofIndex {
  std::map<std::string, int> body_offset;
  FeDofIndex fe;
  int body_dofs = 0;
  int n = 0;
};

}  // namespace assembly

namespace {

using assembly::Coeffs;
using assembly::DofIndex;
using assembly::Triplets;

/// Displacement / rotation of an anchor as linear combinations of system DOFs.
struct Kinematics {
  std::array<Coeffs, 3> u;
  std::array<Coeffs, 3> theta;
  std::array<bool, 3> has_u{true, true, true};
  std::array<bool, 3> has_theta{true, true, true};
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  bool ground = false;
};

DofIndex BuildIndex(const Model& model) {
  DofIndex index;
  for (const Body& b : model.bodies) {
    if (b.name == kGround) throw InputError(model.Where(b.line), "body name 'ground' is reserved for the fixed support");
    if (index.body_offset.count(b.name)) throw InputError(model.Where(b.line), "duplicate body name '" + b.name + "'");
    index.body_offset[b.name] = index.n;
    index.n += 6;
  }
  index.body_dofs = index.n;
  const FeMatrices& fe = model.fe;
  if (!fe.Empty()) {
    const auto rows = static_cast<Eigen::Index>(fe.dofs.size());
    // Every FE matrix ([fe] and parts) is n x n in the DOF map's order; 0 x 0 means "none".
    auto check = [&](const Eigen::SparseMatrix<double>& a, const std::string& file, const std::string& where) {
      if (a.rows() == 0 && a.cols() == 0) return;
      if (a.rows() != rows || a.cols() != rows)
        throw InputError(where, (file.empty() ? std::string("matrix") : file) + " is " + std::to_string(a.rows()) + "x" +
                                    std::to_string(a.cols()) + " but the [fe] DOF map has " + std::to_string(rows) +
                                    " rows: expected a " + std::to_string(rows) + "x" + std::to_string(rows) +
                                    " matrix in the DOF map's order");
    };
    check(fe.mass, fe.mass_file, fe.origin);
    check(fe.stiffness, fe.stiffness_file, fe.origin);
    for (const FePart& part : fe.parts) {
      const std::string where = model.Where(part.line) + ": part '" + part.name + "'";
      if (part.stiffness) check(*part.stiffness, part.stiffness_file, where);
      if (part.mass) check(*part.mass, part.mass_file, where);
    }
    index.fe.sorted.reserve(fe.dofs.size());
    for (std::size_t i = 0; i < fe.dofs.size(); ++i) {
      const auto& d = fe.dofs[i];
      if (d.dof < 1 || d.dof > 6)
        throw InputError(fe.origin, "[fe] DOF map row " + std::to_string(i + 1) + ": dof " + std::to_string(d.dof) +
                                        " not in 1..6");
      index.fe.sorted.push_back({{d.node, d.dof}, index.n + static_cast<int>(i)});
    }
    // Sorted by (node, dof), then by row: of two equal entries the second is the later row.
    std::sort(index.fe.sorted.begin(), index.fe.sorted.end());
    for (std::size_t k = 1; k < index.fe.sorted.size(); ++k)
      if (index.fe.sorted[k].first == index.fe.sorted[k - 1].first) {
        // The first row that repeats an earlier one, as a reading in row order finds it.
        std::size_t first_repeat = k;
        for (std::size_t j = k; j < index.fe.sorted.size(); ++j)
          if (index.fe.sorted[j].first == index.fe.sorted[j - 1].first &&
              index.fe.sorted[j].second < index.fe.sorted[first_repeat].second)
            first_repeat = j;
        const auto& [key, at] = index.fe.sorted[first_repeat];
        throw InputError(fe.origin, "[fe] DOF map row " + std::to_string(at - index.n + 1) + ": node " +
                                        std::to_string(key.first) + " dof " + std::to_string(key.second) + " appears twice");
      }
    index.n += static_cast<int>(rows);
  }
  return index;
}

std::string BodyList(const Model& model) {
  std::string s;
  for (const Body& b : model.bodies) s += (s.empty() ? "" : ", ") + b.name;
  return s + (s.empty() ? "" : ", ") + kGround;
}

// `fe`: the model's [fe] DOF map and node positions (the model's own, or those of the model a
// RestAssembler was made for: effects never change them).
Kinematics Resolve(const Model& model, const FeMatrices& fe, const DofIndex& index, const Anchor& anchor,
                   const Eigen::Vector3d* default_at, const std::string& where, const std::string& what) {
  Kinematics k;
  if (anchor.IsNode()) {
    if (fe.Empty())
      throw InputError(where, what + " refers to FE node " + std::to_string(anchor.node) + " but the model has no [fe]");
    bool any = false;
    for (int i = 0; i < 3; ++i) {
      const int u = index.fe.Find(anchor.node, i + 1);
      k.has_u[i] = u >= 0;
      if (k.has_u[i]) k.u[i].push_back({u, 1.0}), any = true;
      const int theta = index.fe.Find(anchor.node, i + 4);
      k.has_theta[i] = theta >= 0;
      if (k.has_theta[i]) k.theta[i].push_back({theta, 1.0}), any = true;
    }
    if (!any) throw InputError(where, what + " refers to FE node " + std::to_string(anchor.node) + ", which has no DOF in the [fe] DOF map");
    auto pos = fe.node_positions.find(anchor.node);
    if (pos != fe.node_positions.end()) k.position = pos->second;
    return k;
  }
  if (anchor.IsGround()) {
    k.ground = true;
    k.position = anchor.has_at ? anchor.at : (default_at ? *default_at : Eigen::Vector3d::Zero());
    return k;
  }
  auto it = index.body_offset.find(anchor.body);
  if (it == index.body_offset.end())
    throw InputError(where, what + " refers to unknown body '" + anchor.body + "' (known: " + BodyList(model) + ")");
  const Body& body = *model.FindBody(anchor.body);
  const int o = it->second;
  k.position = anchor.has_at ? anchor.at : (default_at ? *default_at : body.centre);
  const Eigen::Vector3d r = k.position - body.centre;
  // u = u0 + theta x r
  k.u[0] = {{o + 0, 1.0}, {o + 4, r.z()}, {o + 5, -r.y()}};
  k.u[1] = {{o + 1, 1.0}, {o + 5, r.x()}, {o + 3, -r.z()}};
  k.u[2] = {{o + 2, 1.0}, {o + 3, r.y()}, {o + 4, -r.x()}};
  for (int i = 0; i < 3; ++i) k.theta[i] = {{o + 3 + i, 1.0}};
  return k;
}

void AddOuter(double scale, const Coeffs& g, Triplets* t) {
  for (const auto& [p, cp] : g)
    for (const auto& [q, cq] : g) t->emplace_back(p, q, scale * cp * cq);
}

void AddPointMass(const Model& model, const FeMatrices& fe, const DofIndex& index, const PointMass& pm, Triplets* t) {
  const std::string where = model.Where(pm.line);
  if (!(pm.mass >= 0.0) || !std::isfinite(pm.mass))
    throw InputError(where, "mass '" + pm.name + "': mass must be >= 0, got " + std::to_string(pm.mass));
  const Kinematics k = Resolve(model, fe, index, pm.where, nullptr, where, "mass '" + pm.name + "'");
  if (k.ground) return;  // a mass on the fixed support does not move
  for (int i = 0; i < 3; ++i) AddOuter(pm.mass, k.u[i], t);
}

const Setup* FindSetup(const Model& model, const std::string& name) {
  if (name.empty()) return nullptr;
  for (const Setup& s : model.setups)
    if (s.name == name) return &s;
  std::string known;
  for (const Setup& s : model.setups) known += (known.empty() ? "" : ", ") + s.name;
  throw InputError(model.origin.empty() ? "model" : model.origin,
                   "unknown setup '" + name + "' (setups: " + (known.empty() ? "none" : known) + ")");
}

// What is not an FE matrix — bodies, point masses (the options' extra masses too) and springs at
// the operating point of `options.setup` — as triplets of M and K in the numbering of `index`;
// `sys` (may be null) gets the bodies' DOF names and the springs' states and coefficients.
void AddRest(const Model& model, const FeMatrices& fe, const DofIndex& index, const SolveOptions& options, Triplets* mt,
             Triplets* kt, System* sys) {
  const Setup* setup = FindSetup(model, options.setup);
  if (setup) {
    std::set<std::string> groups;
    for (const Spring& s : model.springs) groups.insert(s.group);
    for (const auto& [group, value] : setup->operating)
      if (!groups.count(group)) {
        std::string known;
        for (const auto& g : groups) known += (known.empty() ? "" : ", ") + g;
        throw InputError(model.Where(setup->line), "setup '" + setup->name + "': operating value for unknown spring group '" +
                                                       group + "' (groups: " + known + ")");
      }
  }
  for (const Body& b : model.bodies) {
    const auto at = index.body_offset.find(b.name);
    if (at == index.body_offset.end())
      throw InputError(model.Where(b.line), "body '" + b.name + "' is not a body of the assembled layout");
    const int o = at->second;
    const std::string where = model.Where(b.line);
    if (!(b.mass >= 0.0) || !(b.inertia.minCoeff() >= 0.0))
      throw InputError(where, "body '" + b.name + "': mass and inertia must be >= 0");
    for (int i = 0; i < 3; ++i) mt->emplace_back(o + i, o + i, b.mass);
    Eigen::Matrix3d j;
    j << b.inertia.x(), -b.products.x(), -b.products.z(),  //
        -b.products.x(), b.inertia.y(), -b.products.y(),   //
        -b.products.z(), -b.products.y(), b.inertia.z();
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c)
        if (j(r, c) != 0.0) mt->emplace_back(o + 3 + r, o + 3 + c, j(r, c));
    static const char* kDofNames[] = {"ux", "uy", "uz", "rx", "ry", "rz"};
    if (sys)
      for (int i = 0; i < 6; ++i) sys->dof_names.push_back(b.name + ":" + kDofNames[i]);
  }
  for (const PointMass& pm : model.masses) AddPointMass(model, fe, index, pm, mt);
  for (const PointMass& pm : options.extra_masses) AddPointMass(model, fe, index, pm, mt);

  for (const Spring& s : model.springs) {
    const std::string where = model.Where(s.line);
    const std::string what = "spring '" + s.name + "'";
    const double norm = s.direction.norm();
    if (!(norm > 0.0) || !std::isfinite(norm)) throw InputError(where, what + ": direction must be a non-zero vector");
    const Eigen::Vector3d n_dir = s.direction / norm;
    const Kinematics a = Resolve(model, fe, index, s.a, nullptr, where, what + " end a");
    const Kinematics b = Resolve(model, fe, index, s.b, &a.position, where, what + " end b");
    if (a.ground && b.ground) throw InputError(where, what + ": both ends on ground");
    double override_value = kNaN;
    if (setup) {
      auto it = setup->operating.find(s.group);
      if (it != setup->operating.end() && s.law.IsNonlinear()) override_value = it->second;
    }
    SpringState state = LinearizeLaw(s.law, where + ": " + what, override_value);
    state.name = s.name;
    state.group = s.group;
    state.stiffness *= s.stiffness_factor;
    Coeffs g;
    const bool rot = s.kind == Spring::Kind::kRotational;
    for (int i = 0; i < 3; ++i) {
      if (n_dir[i] == 0.0) continue;
      for (const Kinematics* end : {&a, &b}) {
        const bool has = rot ? end->has_theta[i] : end->has_u[i];
        if (!has)
          throw InputError(where, what + ": FE node " + std::to_string(end == &a ? s.a.node : s.b.node) + " has no " +
                                      (rot ? "rotation" : "translation") + " DOF " + std::to_string(i + (rot ? 4 : 1)));
        const double sign = end == &a ? 1.0 : -1.0;
        for (const auto& [dof, c] : (rot ? end->theta[i] : end->u[i])) g.emplace_back(dof, sign * n_dir[i] * c);
      }
    }
    AddOuter(state.stiffness, g, kt);
    if (sys) {
      sys->springs.push_back(std::move(state));
      sys->spring_coefficients.push_back(std::move(g));
    }
  }
}

}  // namespace

System Assemble(const Model& model, const SolveOptions& options, FeAssembly fe_matrices) {
  const DofIndex index = BuildIndex(model);
  System sys;
  sys.body_dof_count = index.body_dofs;
  const int n = index.n;
  Triplets mt, kt;
  AddRest(model, model.fe, index, options, &mt, &kt, &sys);
  if (!model.fe.Empty()) {
    const int o = index.body_dofs;
    auto add = [&](const Eigen::SparseMatrix<double>& src, double factor, Triplets* t) {
      if (src.rows() == 0 || factor == 0.0) return;
      for (int c = 0; c < src.outerSize(); ++c)
        for (Eigen::SparseMatrix<double>::InnerIterator it(src, c); it; ++it)
          t->emplace_back(o + static_cast<int>(it.row()), o + static_cast<int>(it.col()), factor * it.value());
    };
    if (fe_matrices == FeAssembly::kAll) {
      add(model.fe.mass, 1.0, &mt);
      add(model.fe.stiffness, 1.0, &kt);
      for (const FePart& part : model.fe.parts) {
        if (part.mass) add(*part.mass, part.mass_factor, &mt);
        if (part.stiffness) add(*part.stiffness, part.stiffness_factor, &kt);
      }
    }
    for (std::size_t i = 0; i < model.fe.dofs.size(); ++i) {
      static const char* kDofNames[] = {"ux", "uy", "uz", "rx", "ry", "rz"};
      sys.dof_names.push_back("fe:" + std::to_string(model.fe.dofs[i].node) + ":" + kDofNames[model.fe.dofs[i].dof - 1]);
    }
  }
  sys.mass.resize(n, n);
  sys.mass.setFromTriplets(mt.begin(), mt.end());
  sys.stiffness.resize(n, n);
  sys.stiffness.setFromTriplets(kt.begin(), kt.end());

  Triplets ot;
  std::set<int> ids;
  for (const TestPoint& p : model.points) {
    const std::string where = model.Where(p.line);
    if (!ids.insert(p.id).second) throw InputError(where, "test point id " + std::to_string(p.id) + " appears twice");
    const Kinematics k = Resolve(model, model.fe, index, p.where, nullptr, where, "point " + std::to_string(p.id));
    const int row0 = static_cast<int>(sys.observed_dofs.size());
    for (int i = 0; i < 3; ++i) {
      sys.observed_dofs.push_back({p.id, i + 1});
      for (const auto& [dof, c] : k.u[i]) ot.emplace_back(row0 + i, dof, c);
    }
    sys.geometry.push_back({p.id, k.position});
  }
  sys.observation.resize(static_cast<int>(sys.observed_dofs.size()), n);
  sys.observation.setFromTriplets(ot.begin(), ot.end());
  return sys;
}

struct detail::RestAssembler::Layout {
  DofIndex index;
  FeMatrices fe;  ///< the DOF map and node positions only (no matrix, no part)
  std::vector<std::string> bodies;
};

detail::RestAssembler::RestAssembler(const Model& layout) : layout_(std::make_unique<Layout>()) {
  layout_->index = BuildIndex(layout);
  layout_->fe.dofs = layout.fe.dofs;
  layout_->fe.node_positions = layout.fe.node_positions;
  for (const Body& b : layout.bodies) layout_->bodies.push_back(b.name);
}

detail::RestAssembler::~RestAssembler() = default;

bool detail::RestAssembler::Fits(const Model& model) const {
  if (model.bodies.size() != layout_->bodies.size()) return false;
  for (std::size_t b = 0; b < model.bodies.size(); ++b)
    if (model.bodies[b].name != layout_->bodies[b]) return false;
  return true;
}

void detail::RestAssembler::Assemble(const Model& model, const SolveOptions& options, Triplets* mass,
                                     Triplets* stiffness) const {
  AddRest(model, layout_->fe, layout_->index, options, mass, stiffness, nullptr);
}

namespace {

/// (K - sigma M)^-1 x with a factorisation made beforehand (sparse_factor.hpp), for Spectra's
/// shift-invert mode (its constructor sets the same shift again: nothing to do).
class FactorShiftInvert {
 public:
  using Scalar = double;
  explicit FactorShiftInvert(const detail::SparseFactor& factor, Eigen::Index n) : factor_(factor), n_(n) {}
  Eigen::Index rows() const { return n_; }
  Eigen::Index cols() const { return n_; }
  void set_shift(double) {}
  void perform_op(const double* x_in, double* y_out) const {
    Eigen::Map<const Eigen::VectorXd> x(x_in, n_);
    Eigen::Map<Eigen::VectorXd> y(y_out, n_);
    y.noalias() = factor_.Solve(x);
  }

 private:
  const detail::SparseFactor& factor_;
  Eigen::Index n_;
};

// Where system DOF i comes from, for messages: its body's line in the model file, or the FE
// matrix file and its diagonal entry.
std::string DofWhere(const Model& model, const System& sys, int i, bool stiffness) {
  if (i < sys.body_dof_count) {
    const std::size_t b = static_cast<std::size_t>(i / 6);
    return b < model.bodies.size() ? model.Where(model.bodies[b].line) : model.Where(0);
  }
  const int r = i - sys.body_dof_count + 1;
  const std::string& file = stiffness ? model.fe.stiffness_file : model.fe.mass_file;
  return (file.empty() ? model.fe.origin : file) + ": entry (" + std::to_string(r) + ", " + std::to_string(r) + ")";
}

// The DOFs without mass: FE DOFs whose whole row of M is zero (rotations of a lumped-mass export,
// the internal DOFs of a condensed element) are normal input and returned; a body DOF without mass
// or inertia, a negative diagonal, or a zero diagonal with off-diagonal mass is an error.
std::vector<int> MasslessDofs(const Model& model, const System& sys) {
  const Eigen::VectorXd diag = sys.mass.diagonal();
  std::vector<int> massless;
  std::vector<char> coupled(static_cast<std::size_t>(diag.size()), 0);
  for (int c = 0; c < sys.mass.outerSize(); ++c)
    for (Eigen::SparseMatrix<double>::InnerIterator it(sys.mass, c); it; ++it)
      if (it.row() != it.col() && it.value() != 0.0) coupled[static_cast<std::size_t>(it.row())] = 1;
  for (int i = 0; i < diag.size(); ++i) {
    if (diag[i] > 0.0) continue;
    if (i < sys.body_dof_count || diag[i] < 0.0 || !std::isfinite(diag[i]))
      throw InputError(DofWhere(model, sys, i, false), "singular mass matrix: DOF " + sys.dof_names[i] +
                                                           " has no mass or inertia (diagonal entry " +
                                                           std::to_string(diag[i]) + "): expected a mass > 0 and " +
                                                           "inertia > 0 about every axis");
    if (coupled[static_cast<std::size_t>(i)])
      throw InputError(DofWhere(model, sys, i, false),
                       "mass matrix not positive semi-definite: DOF " + sys.dof_names[i] +
                           " has no mass on the diagonal but mass coupling to other DOFs");
    massless.push_back(i);
  }
  return massless;
}

// The first DOF k at which the Cholesky factorisation of the dense SPD candidate `m` fails: the
// leading k+1 DOFs are not positive definite. -1 when it succeeds.
int FirstNonPositivePivot(Eigen::MatrixXd m) {
  const int n = static_cast<int>(m.rows());
  for (int k = 0; k < n; ++k) {
    const double d = m(k, k) - m.row(k).head(k).squaredNorm();
    if (!(d > 0.0)) return k;
    m(k, k) = std::sqrt(d);
    for (int i = k + 1; i < n; ++i) m(i, k) = (m(i, k) - m.row(i).head(k).dot(m.row(k).head(k))) / m(k, k);
  }
  return -1;
}

}  // namespace

Solution Solve(const Model& input, const SolveOptions& options) { return detail::SolveKeepingFactor(input, options, nullptr); }

Solution detail::SolveKeepingFactor(const Model& input, const SolveOptions& options,
                                    std::unique_ptr<SparseFactor>* kept_factor, System* kept_system) {
  if (kept_factor) kept_factor->reset();
  const Model applied = input.effects.empty() ? Model() : ApplyEffects(input);
  const Model& model = input.effects.empty() ? input : applied;
  const std::string origin = model.origin.empty() ? "model" : model.origin;
  System sys = Assemble(model, options);
  const int n = static_cast<int>(sys.mass.rows());
  double sparse_scale = 0.0;
  if (n == 0) throw InputError(origin, "the model has no degrees of freedom (no [[body]] and no [fe])");
  const std::vector<int> massless = MasslessDofs(model, sys);

  Solution sol;
  sol.springs = sys.springs;
  sol.dof_names = sys.dof_names;
  Eigen::VectorXd eigenvalues;
  Eigen::MatrixXd vectors;
  if (n < options.sparse_threshold) {
    const Eigen::MatrixXd m(sys.mass), k(sys.stiffness);
    // Massless DOFs carry no inertia: condensing them statically (K_mm - K_mz K_zz^-1 K_zm on the
    // DOFs with mass) is exact for every finite eigenvalue, and keeps M positive definite.
    std::vector<int> keep;
    {
      std::vector<char> drop(static_cast<std::size_t>(n), 0);
      for (int i : massless) drop[static_cast<std::size_t>(i)] = 1;
      for (int i = 0; i < n; ++i)
        if (!drop[static_cast<std::size_t>(i)]) keep.push_back(i);
    }
    if (keep.empty()) throw InputError(origin, "the model has no mass: every DOF of the [fe] mass matrix is zero");
    Eigen::MatrixXd recover;  // massless DOFs = recover * DOFs with mass
    Eigen::MatrixXd mk = m, kk = k;
    if (!massless.empty()) {
      const Eigen::MatrixXd kzz = k(massless, massless);
      Eigen::LLT<Eigen::MatrixXd> lzz(kzz);
      if (lzz.info() != Eigen::Success) {
        const int z = std::max(0, FirstNonPositivePivot(kzz));
        const int dof = massless[static_cast<std::size_t>(z)];
        throw InputError(DofWhere(model, sys, dof, true),
                         "DOF " + sys.dof_names[static_cast<std::size_t>(dof)] +
                             " has no mass and nothing holds it: the stiffness of the massless DOFs is singular "
                             "(a rotation no element connects?); expected every massless DOF to be held by stiffness");
      }
      recover = -lzz.solve(k(massless, keep));
      kk = k(keep, keep) + k(keep, massless) * recover;
      kk = 0.5 * (kk + kk.transpose()).eval();
      mk = m(keep, keep);
    }
    Eigen::LLT<Eigen::MatrixXd> llt(mk);
    if (llt.info() != Eigen::Success) {
      const int bad = keep[static_cast<std::size_t>(std::max(0, FirstNonPositivePivot(mk)))];
      throw InputError(DofWhere(model, sys, bad, false),
                       "singular mass matrix: M is not positive definite at DOF " + sys.dof_names[bad] +
                           " (a body with zero mass or inertia, products of inertia larger than the inertias, "
                           "or an FE mass matrix that is not positive definite)");
    }
    Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> es(kk, mk, Eigen::ComputeEigenvectors | Eigen::Ax_lBx);
    if (es.info() != Eigen::Success) throw InputError(origin, "eigenvalue solution failed");
    eigenvalues = es.eigenvalues();
    if (massless.empty()) {
      vectors = es.eigenvectors();  // M-normalised by Eigen
    } else {
      vectors.resize(n, eigenvalues.size());
      vectors(keep, Eigen::all) = es.eigenvectors();
      vectors(massless, Eigen::all) = recover * es.eigenvectors();
    }
  } else {
    sol.sparse = true;
    const int wanted = options.max_modes > 0 ? options.max_modes : 30;
    const int nev = std::min(n - 1, wanted + 6);  // room for up to 6 rigid-body modes
    const int ncv = std::min(n, std::max(2 * nev + 1, nev + 20));
    // Massless DOFs get a mass 1e-12 of the largest: their spurious modes lie far above the
    // lowest ones the shift-invert iteration finds, whose change is of that order.
    Eigen::SparseMatrix<double> mass = sys.mass;
    if (!massless.empty()) {
      const double tiny = 1e-12 * mass.diagonal().maxCoeff();
      // As a diagonal matrix added at once (coeffRef inserting one entry at a time is quadratic).
      std::vector<Eigen::Triplet<double>> diag;
      for (int i : massless) diag.emplace_back(i, i, tiny);
      Eigen::SparseMatrix<double> extra(n, n);
      extra.setFromTriplets(diag.begin(), diag.end());
      mass += extra;
    }
    // Shift slightly below zero so K - sigma M is definite even with rigid-body modes, and no
    // further: the lowest modes converge by how far apart they lie after the shift-inversion.
    const double scale = sys.stiffness.diagonal().sum() / mass.diagonal().sum();
    const double sigma = -std::max(1.0, options.sparse_shift * scale);
    auto factor = std::make_unique<detail::SparseFactor>();
    if (!factor->Compute(Eigen::SparseMatrix<double>(sys.stiffness - sigma * mass)))
      throw InputError(origin, "sparse factorisation of K - sigma M failed");
    // Block Lanczos (block_lanczos.hpp) where the basis is small beside the model — every FE-sized
    // model; Spectra's single-vector Lanczos for the few hundred DOFs below that.
    detail::BlockLanczosOptions lanczos;
    lanczos.wanted = nev;
    lanczos.block_size = std::clamp(nev / 3, 4, 12);
    // Converged: the elastic pairs kept and the rigid-body ones below them — not the room above.
    lanczos.converged_elastic = std::min(wanted, nev);
    lanczos.rigid_limit = std::max(std::pow(kTwoPi * options.rigid_frequency_hz, 2), options.rigid_tolerance * scale);
    // A basis of five times the pairs: one restart instead of four at 220 941 DOFs (18.3 → 16.0 s
    // for 30 modes); models below four such bases keep the default basis (docs/model.md).
    const bool block_path = n >= 4 * detail::BasisColumns(lanczos);
    lanczos.max_basis = 5 * nev;
    if (n < 4 * detail::BasisColumns(lanczos)) lanczos.max_basis = 0;
    if (block_path) {
      const detail::BlockLanczosSummary summary = detail::LowestEigenpairs(*factor, sigma, mass, lanczos);
      if (!summary.converged)
        throw ConvergenceError(origin, "sparse eigenvalue solution did not converge (block Lanczos, " +
                                           std::to_string(summary.block_solves) + " block solves)");
      eigenvalues = summary.eigenvalues;
      vectors = summary.vectors;
      sol.shift_invert_solves = summary.columns_solved;
    } else {
      FactorShiftInvert op(*factor, n);
      Spectra::SparseSymMatProd<double> bop(mass);
      Spectra::SymGEigsShiftSolver<FactorShiftInvert, Spectra::SparseSymMatProd<double>, Spectra::GEigsMode::ShiftInvert>
          solver(op, bop, nev, ncv, sigma);
      solver.init();
      solver.compute(Spectra::SortRule::LargestMagn, 1000, 1e-10, Spectra::SortRule::SmallestAlge);
      if (solver.info() != Spectra::CompInfo::Successful)
        throw ConvergenceError(origin, "sparse eigenvalue solution did not converge");
      eigenvalues = solver.eigenvalues();
      vectors = solver.eigenvectors();
      sol.shift_invert_solves = static_cast<int>(solver.num_operations());
    }
    // The eigenvalues as Rayleigh quotients of the vectors with the assembled K and M. With σ just
    // below zero the shift-invert solves are accurate only to about ε·λmax/(λ − σ), and λ = σ + 1/θ
    // inherits it: on the 50 004-DOF frame the lowest frequency moved by 1e-3 at random from one
    // part factor to the next (0.8593 Hz for a slightly stiffer model than one at 0.8601). The
    // quotient's error is second order in the vector's: the same steps then agree with the reduced
    // model to 2e-5 (docs/model.md "Eigenvalues from Rayleigh quotients").
    {
      const Eigen::MatrixXd kv = sys.stiffness * vectors, mv = mass * vectors;
      for (Eigen::Index j = 0; j < eigenvalues.size(); ++j)
        eigenvalues(j) = vectors.col(j).dot(kv.col(j)) / vectors.col(j).dot(mv.col(j));
      // In ascending order again (two modes closer than the solves' error may swap).
      std::vector<Eigen::Index> order(static_cast<std::size_t>(eigenvalues.size()));
      for (std::size_t j = 0; j < order.size(); ++j) order[j] = static_cast<Eigen::Index>(j);
      std::stable_sort(order.begin(), order.end(), [&](Eigen::Index a, Eigen::Index b) { return eigenvalues(a) < eigenvalues(b); });
      if (!std::is_sorted(order.begin(), order.end())) {  // the copies are n × modes: only when needed
        const Eigen::VectorXd values = eigenvalues;
        const Eigen::MatrixXd columns = vectors;
        for (std::size_t j = 0; j < order.size(); ++j) {
          eigenvalues(static_cast<Eigen::Index>(j)) = values(order[j]);
          vectors.col(static_cast<Eigen::Index>(j)) = columns.col(order[j]);
        }
      }
    }
    if (kept_factor) *kept_factor = std::move(factor);
    sparse_scale = scale;
  }
  const double lambda_max = eigenvalues.cwiseAbs().maxCoeff();
  // The sparse path only sees the lowest eigenvalues: its relative limit is to trace(K)/trace(M),
  // a mean of all eigenvalues (round-off of a zero eigenvalue in a free-free FE model is of the
  // order of 1e-16 of it).
  const double abs_limit = std::pow(kTwoPi * options.rigid_frequency_hz, 2);
  const double rigid_limit = std::max(abs_limit, options.rigid_tolerance * (sol.sparse ? sparse_scale : lambda_max));
  std::vector<int> elastic;
  for (int i = 0; i < eigenvalues.size(); ++i) {
    const double lam = eigenvalues[i];
    if (lam < -rigid_limit) {
      // Name the DOF that moves most in the offending mode (and its FE entry or body line).
      Eigen::Index k = 0;
      vectors.col(i).cwiseAbs().maxCoeff(&k);
      throw InputError(DofWhere(model, sys, static_cast<int>(k), true),
                       "negative eigenvalue " + std::to_string(lam) +
                           " (rad/s)^2: the stiffness matrix is not positive semi-definite (the mode moves mostly DOF " +
                           sys.dof_names[static_cast<std::size_t>(k)] + "); expected a positive semi-definite stiffness");
    }
    if (lam <= rigid_limit) sol.rigid_body_frequencies_hz.push_back(std::sqrt(std::max(0.0, lam)) / kTwoPi);
    else elastic.push_back(i);
  }
  if (options.max_modes > 0 && static_cast<int>(elastic.size()) > options.max_modes) elastic.resize(options.max_modes);
  if (elastic.empty())
    sol.warnings.push_back(origin + ": no elastic mode: all " + std::to_string(sol.rigid_body_frequencies_hz.size()) +
                           " modes are rigid-body modes (a free model with no spring or support between its parts?)");

  sol.full_shapes.resize(n, static_cast<int>(elastic.size()));
  sol.modes.dofs = sys.observed_dofs;
  sol.modes.geometry = sys.geometry;
  sol.modes.source = (model.name.empty() ? origin : model.name) + (options.setup.empty() ? "" : " [" + options.setup + "]");
  for (std::size_t j = 0; j < elastic.size(); ++j) {
    const Eigen::VectorXd phi = vectors.col(elastic[j]);
    sol.full_shapes.col(static_cast<int>(j)) = phi;
    Mode mode;
    mode.frequency_hz = std::sqrt(eigenvalues[elastic[j]]) / kTwoPi;
    mode.damping_ratio = model.damping.RatioOfMode(static_cast<int>(j));
    mode.pole = FrequencyAndDampingToPole(mode.frequency_hz, mode.damping_ratio);
    mode.shape = (sys.observation * phi).cast<std::complex<double>>();
    mode.mpc = 1.0;
    mode.mpd = 0.0;
    mode.unit_modal_mass = true;
    sol.modes.modes.push_back(std::move(mode));
  }
  // Kinetic-energy shares: phi^T M_block phi per body (point masses belong to their body's block)
  // and for the FE part; they sum to 1 for a mass-normalised mode.
  const int nm = static_cast<int>(elastic.size());
  const Eigen::MatrixXd mphi = sys.mass * sol.full_shapes;
  for (std::size_t b = 0; b < model.bodies.size(); ++b) {
    EnergyShare e{model.bodies[b].name, std::vector<double>(nm)};
    const int o = static_cast<int>(b) * 6;
    for (int j = 0; j < nm; ++j) e.share[j] = sol.full_shapes.col(j).segment(o, 6).dot(mphi.col(j).segment(o, 6));
    sol.energy.push_back(std::move(e));
  }
  if (!model.fe.Empty()) {
    EnergyShare e{"fe", std::vector<double>(nm)};
    const int o = sys.body_dof_count, len = n - o;
    for (int j = 0; j < nm; ++j) e.share[j] = sol.full_shapes.col(j).segment(o, len).dot(mphi.col(j).segment(o, len));
    sol.energy.push_back(std::move(e));
  }
  if (kept_system) *kept_system = std::move(sys);
  return sol;
}

std::string Explain(const Solution& sol) {
  std::ostringstream out;
  out.setf(std::ios::fixed);
  out.precision(4);
  out << "Springs (operating point and linearised stiffness):\n";
  for (const SpringState& s : sol.springs) {
    out << "  " << s.name << " [" << s.group << ", " << s.law << "]: force " << s.force << " N, compression "
        << s.deflection * 1e6 << " um, k = " << s.stiffness * 1e-6 << " N/um\n";
    if (!std::isnan(s.gap)) out << "    gap h = " << s.gap * 1e6 << " um\n";
    for (std::size_t i = 0; i < s.element_deflections.size(); ++i)
      out << "    element " << i + 1 << ": " << (std::isnan(s.gap) || s.element_deflections[i] != s.gap ? "compression " : "gap ")
          << s.element_deflections[i] * 1e6 << " um, k = " << s.element_stiffnesses[i] * 1e-6 << " N/um\n";
  }
  out << "Rigid-body modes: " << sol.rigid_body_frequencies_hz.size() << "\n";
  out << "Modes (kinetic-energy share per body, %):\n";
  for (std::size_t j = 0; j < sol.modes.modes.size(); ++j) {
    out << "  mode " << j + 1 << ": " << std::setprecision(2) << sol.modes.modes[j].frequency_hz << " Hz";
    out.precision(1);
    for (const EnergyShare& e : sol.energy) out << "  " << e.body << " " << 100.0 * e.share[j];
    out.precision(4);
    out << "\n";
  }
  return out.str();
}

}  // namespace ema::model
