// `ema fe-import`'s parts (fe_import.hpp): the difference of two assemblies, sparse, with the
// checks the bolted-frame sample's script made on dense matrices (docs/fe-parts.md).
#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <optional>
#include <sstream>
#include <unordered_map>
#include <string>
#include <vector>

#include "ema/core/error.hpp"
#include "ema/formats/atomic_file.hpp"
#include "ema/formats/fe_import.hpp"
#include "ema/formats/matrix_market.hpp"
#include "ema/model/definiteness.hpp"

namespace ema::formats {

namespace fs = std::filesystem;
using Sparse = Eigen::SparseMatrix<double>;

namespace fe_import_detail {

std::string Relative(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3g", v);
  return text;
}

double MaxAbs(const Sparse& m) {
  double s = 0.0;
  for (Eigen::Index k = 0; k < m.nonZeros(); ++k) s = std::max(s, std::abs(m.valuePtr()[k]));
  return s;
}

struct RunMatrices {
  std::vector<FeDof> dofs;
  Sparse stiffness, mass;
};

// A run's DOF map and stiffness (and mass when asked), checked against the nominal DOF map when given.
RunMatrices ReadRun(const FeRun& run, bool with_mass, const std::vector<FeDof>* nominal_dofs,
                    const fs::path& nominal_map_file, double symmetry_tolerance) {
  RunMatrices r;
  if (run.code == FeRun::Code::kCalculix) {
    r.dofs = ReadCalculixDofs(run.dofs);
    if (nominal_dofs) {
      const std::size_t n = std::min(r.dofs.size(), nominal_dofs->size());
      for (std::size_t i = 0; i < n; ++i)
        if (r.dofs[i] != (*nominal_dofs)[i])
          throw InputError(run.dofs.string() + ":" + std::to_string(i + 1),
                           "DOF " + FeDofText(r.dofs[i]) + " where the nominal run's DOF map (" +
                               nominal_map_file.string() + ":" + std::to_string(i + 1) + ") has " +
                               FeDofText((*nominal_dofs)[i]) +
                               ": the runs numbered the DOFs differently (every run must be the same mesh "
                               "with the same boundary conditions)");
      if (r.dofs.size() != nominal_dofs->size())
        throw InputError(run.dofs.string(), std::to_string(r.dofs.size()) + " DOFs, the nominal run's DOF map (" +
                                                nominal_map_file.string() + ") " +
                                                std::to_string(nominal_dofs->size()) +
                                                ": the runs numbered the DOFs differently");
    }
    const auto n = static_cast<Eigen::Index>(r.dofs.size());
    r.stiffness = ReadCalculixMatrix(run.stiffness, n);
    if (with_mass && !run.mass.empty()) r.mass = ReadCalculixMatrix(run.mass, n);
    return r;
  }
  AbaqusMatrix k = ReadAbaqusMatrix(run.stiffness, nullptr, symmetry_tolerance);
  if (nominal_dofs && k.dofs != *nominal_dofs) {
    // Name the first label that one map has and the other has not.
    std::vector<FeDof> extra, missing;
    std::set_difference(k.dofs.begin(), k.dofs.end(), nominal_dofs->begin(), nominal_dofs->end(),
                        std::back_inserter(extra));
    std::set_difference(nominal_dofs->begin(), nominal_dofs->end(), k.dofs.begin(), k.dofs.end(),
                        std::back_inserter(missing));
    throw InputError(run.stiffness.string(),
                     std::to_string(k.dofs.size()) + " DOFs, the nominal run (" + nominal_map_file.string() + ") " +
                         std::to_string(nominal_dofs->size()) +
                         (extra.empty() ? "" : "; DOF " + FeDofText(extra.front()) + " is not in the nominal run") +
                         (missing.empty() ? "" : "; the nominal run's DOF " + FeDofText(missing.front()) +
                                                     " is not in this one") +
                         ": the runs numbered the DOFs differently");
  }
  r.dofs = std::move(k.dofs);
  r.stiffness = std::move(k.lower);
  if (with_mass && !run.mass.empty()) r.mass = ReadAbaqusMatrix(run.mass, &r.dofs, symmetry_tolerance).lower;
  return r;
}

// The first entry of `part` (lower triangle) where `pattern` has none: (row, column), or (-1, -1).
std::pair<Eigen::Index, Eigen::Index> OffPattern(const Sparse& part, const Sparse& pattern) {
  for (Eigen::Index c = 0; c < part.outerSize(); ++c) {
    Sparse::InnerIterator q(pattern, c);
    for (Sparse::InnerIterator p(part, c); p; ++p) {
      while (q && q.row() < p.row()) ++q;
      if (!q || q.row() != p.row()) return {p.row(), c};
    }
  }
  return {-1, -1};
}

// Positive semi-definiteness of a part on its own rows: LDLᵀ of K + τI, τ = tolerance × max diagonal.
void RequirePositiveSemiDefinite(const FeImportedPart& part, const std::vector<FeDof>& dofs, double tolerance) {
  const Sparse& k = part.stiffness;
  const Eigen::Index n = k.rows();
  std::vector<Eigen::Index> compact(static_cast<std::size_t>(n), -1), rows;
  for (Eigen::Index c = 0; c < k.outerSize(); ++c)
    for (Sparse::InnerIterator it(k, c); it; ++it) compact[static_cast<std::size_t>(it.row())] = compact[static_cast<std::size_t>(c)] = 0;
  for (Eigen::Index i = 0; i < n; ++i)
    if (compact[static_cast<std::size_t>(i)] == 0) compact[static_cast<std::size_t>(i)] = static_cast<Eigen::Index>(rows.size()), rows.push_back(i);
  const auto m = static_cast<Eigen::Index>(rows.size());
  double max_diag = 0.0;
  std::vector<Eigen::Triplet<double>> t;
  t.reserve(static_cast<std::size_t>(k.nonZeros() + m));
  for (Eigen::Index c = 0; c < k.outerSize(); ++c)
    for (Sparse::InnerIterator it(k, c); it; ++it) {
      t.emplace_back(compact[static_cast<std::size_t>(it.row())], compact[static_cast<std::size_t>(c)], it.value());
      if (it.row() == c) max_diag = std::max(max_diag, it.value());
    }
  const double tau = tolerance * std::max(max_diag, MaxAbs(k));
  for (Eigen::Index i = 0; i < m; ++i) t.emplace_back(i, i, tau);
  Sparse a(m, m);
  a.setFromTriplets(t.begin(), t.end());
  const model::DefinitenessCheck check = model::CheckPositiveDefinite(a);
  if (check.PositiveDefinite()) return;
  const Eigen::Index bad = check.first_failure, negative = check.non_positive_pivots;
  const Eigen::Index row = rows[static_cast<std::size_t>(bad)];
  throw InputError(part.source.string() + ", row " + std::to_string(row + 1) + " (DOF " +
                       FeDofText(dofs[static_cast<std::size_t>(row)]) + ")",
                   "part '" + part.name + "' is not positive semi-definite: the factorisation of K_" + part.name +
                       " + tau*I (tau = " + Relative(tolerance) + " x its largest diagonal) broke there" +
                       (negative > 0 ? " (" + std::to_string(negative) + " eigenvalue" + (negative > 1 ? "s" : "") +
                                           " below -tau)"
                                     : "") +
                       "; a part's stiffness is PSD when it is the stiffness of its own elements — check that its "
                       "run changed only that part's modulus, by the scale given (" +
                       Relative(part.scale) + ")");
}

// Which DOF pairs share an element of a part (or of the rest): the deck's element sets.
class ElementPattern {
 public:
  ElementPattern(const FeElementSets& sets, const std::vector<FePartInput>& parts) : sets_(sets) {
    owner_.assign(sets.nodes.size(), -1);
    for (std::size_t p = 0; p < parts.size(); ++p) {
      const std::vector<int>* elements = sets.Find(parts[p].name);
      if (!elements || elements->empty())
        throw InputError(sets.file.string(), "no element set '" + parts[p].name + "' (part '" + parts[p].name +
                                                 "'): with a deck, each part is named as its *ELSET");
      for (const int e : *elements) {
        if (owner_[static_cast<std::size_t>(e)] >= 0)
          throw InputError(sets.file.string(), "an element is in the sets of two parts, '" +
                                                   parts[static_cast<std::size_t>(owner_[static_cast<std::size_t>(e)])].name +
                                                   "' and '" + parts[p].name + "': parts must be distinct element sets");
        owner_[static_cast<std::size_t>(e)] = static_cast<int>(p);
      }
    }
    for (std::size_t e = 0; e < sets.nodes.size(); ++e)
      for (const long node : sets.nodes[e]) incidence_[node].push_back(static_cast<int>(e));
  }
  /// True when nodes `a` and `b` share an element of part `owner` (-1: an element in no part).
  bool Shares(long a, long b, int owner) const {
    const auto it = incidence_.find(a);
    if (it == incidence_.end()) return false;
    for (const int e : it->second) {
      if (owner_[static_cast<std::size_t>(e)] != owner) continue;
      const std::vector<long>& nodes = sets_.nodes[static_cast<std::size_t>(e)];
      if (std::binary_search(nodes.begin(), nodes.end(), b)) return true;
    }
    return false;
  }
  /// Zeroes the entries of `m` (lower triangle) off the DOF pairs of `owner`'s elements; returns
  /// the largest zeroed and where it was (row, column; -1 when none).
  double ZeroOff(Sparse* m, int owner, const std::vector<FeDof>& dofs, Eigen::Index* row, Eigen::Index* col) const {
    double largest = 0.0;
    *row = *col = -1;
    for (Eigen::Index c = 0; c < m->outerSize(); ++c)
      for (Sparse::InnerIterator it(*m, c); it; ++it) {
        if (it.value() == 0.0 ||
            Shares(dofs[static_cast<std::size_t>(it.row())].node, dofs[static_cast<std::size_t>(c)].node, owner))
          continue;
        if (std::abs(it.value()) > largest) largest = std::abs(it.value()), *row = it.row(), *col = c;
        it.valueRef() = 0.0;
      }
    m->prune(0.0);
    return largest;
  }

 private:
  const FeElementSets& sets_;
  std::vector<int> owner_;
  std::unordered_map<long, std::vector<int>> incidence_;
};

}  // namespace fe_import_detail

bool FeImportOptions::IsValid(std::string* why) const {
  const auto bad = [&](const std::string& text) {
    if (why) *why = text;
    return false;
  };
  if (!(part_tolerance >= 0.0 && part_tolerance < 1e-3)) return bad("part tolerance must be in [0, 1e-3)");
  if (!(rest_tolerance >= 0.0 && rest_tolerance < 1e-3)) return bad("rest tolerance must be in [0, 1e-3)");
  if (!(psd_tolerance >= 0.0 && psd_tolerance < 1e-2)) return bad("PSD tolerance must be in [0, 1e-2)");
  if (!(symmetry_tolerance >= 0.0 && symmetry_tolerance < 1e-2)) return bad("symmetry tolerance must be in [0, 1e-2)");
  return true;
}

FeImport ImportFeParts(const FeRun& nominal, const std::vector<FePartInput>& parts, const FeImportOptions& options,
                       const ProgressCallback& progress, const FeElementSets* elements) {
  using namespace fe_import_detail;
  if (std::string why; !options.IsValid(&why)) throw UsageError(why);
  std::optional<ElementPattern> pattern;
  if (elements) pattern.emplace(*elements, parts);
  const double steps = 2.0 * static_cast<double>(parts.size()) + 2.0;
  double done = 0.0;
  const auto step = [&](const char* stage) { ReportProgress(progress, ++done / steps, stage); };
  ReportProgress(progress, 0.0, "reading the nominal run");
  const fs::path map_file = nominal.code == FeRun::Code::kCalculix ? nominal.dofs : nominal.stiffness;
  RunMatrices k0 = ReadRun(nominal, true, nullptr, map_file, options.symmetry_tolerance);
  step("reading the nominal run");
  FeImport out;
  out.dofs = std::move(k0.dofs);
  out.mass = std::move(k0.mass);
  out.mass.prune(0.0);
  out.max_stiffness = MaxAbs(k0.stiffness);
  const double kmax = out.max_stiffness;
  if (!(kmax > 0.0)) throw InputError(nominal.stiffness.string(), "the nominal stiffness is all zero");
  const auto n = static_cast<Eigen::Index>(out.dofs.size());
  for (std::size_t index = 0; index < parts.size(); ++index) {
    const FePartInput& p = parts[index];
    FeImportedPart part;
    part.name = p.name;
    part.source = p.run.stiffness;
    part.scale = p.scale;
    part.direct = p.direct;
    if (p.direct) {
      if (p.run.code != FeRun::Code::kAbaqus)
        throw UsageError("part '" + p.name + "': a part's own matrix is read from an Abaqus .mtx file");
      part.stiffness = ReadAbaqusMatrix(p.run.stiffness, &out.dofs, options.symmetry_tolerance).lower;
    } else {
      if (!(p.scale > 0.0) || p.scale == 1.0)
        throw UsageError("part '" + p.name + "': the scale of its run must be positive and not 1");
      if (p.run.code != nominal.code)
        throw UsageError("part '" + p.name + "': its run and the nominal run must come from the same FE code");
      RunMatrices ks = ReadRun(p.run, false, &out.dofs, map_file, options.symmetry_tolerance);
      step("reading the parts' runs");
      // K_p = (K_nominal − K_s) / (1 − s), entry by entry as the sample's script did.
      part.stiffness = k0.stiffness - ks.stiffness;
      const double divisor = 1.0 - p.scale;
      for (Eigen::Index k = 0; k < part.stiffness.nonZeros(); ++k) part.stiffness.valuePtr()[k] /= divisor;
    }
    part.stiffness.prune(0.0);  // off the part, both runs print the same numbers: exact zeros
    if (part.stiffness.nonZeros() == 0)
      throw InputError(p.run.stiffness.string(),
                       p.direct ? "part '" + p.name + "': the matrix is all zero"
                                : "part '" + p.name + "': this run's stiffness is the nominal one: no element's "
                                                      "modulus was changed in it");
    if (pattern) {
      // On its own elements' DOF pairs (the sample script's check): round-off elsewhere is zeroed.
      Eigen::Index i = -1, j = -1;
      const double off = pattern->ZeroOff(&part.stiffness, static_cast<int>(index), out.dofs, &i, &j);
      part.largest_dropped = off / kmax;
      if (off > options.part_tolerance * kmax)
        throw InputError(p.run.stiffness.string() + ", row " + std::to_string(i + 1) + " (DOF " +
                             FeDofText(out.dofs[static_cast<std::size_t>(i)]) + ")",
                         "part '" + p.name + "' has stiffness at (" + FeDofText(out.dofs[static_cast<std::size_t>(i)]) +
                             ", " + FeDofText(out.dofs[static_cast<std::size_t>(j)]) + "), " + Relative(off / kmax) +
                             " of max |K|, off its own elements (*ELSET " + p.name + " of " +
                             elements->file.string() + "): its run changed more than that part's elements");
    }
    if (const auto [i, j] = OffPattern(part.stiffness, k0.stiffness); i >= 0)
      throw InputError(p.run.stiffness.string() + ", row " + std::to_string(i + 1) + " (DOF " +
                           FeDofText(out.dofs[static_cast<std::size_t>(i)]) + ")",
                       "part '" + p.name + "' has an entry at (" + FeDofText(out.dofs[static_cast<std::size_t>(i)]) +
                           ", " + FeDofText(out.dofs[static_cast<std::size_t>(j)]) +
                           ") where the nominal stiffness has none: the part is not on the nominal model's DOFs");
    std::vector<char> used(static_cast<std::size_t>(n), 0);
    for (Eigen::Index c = 0; c < part.stiffness.outerSize(); ++c)
      for (Sparse::InnerIterator it(part.stiffness, c); it; ++it) used[static_cast<std::size_t>(it.row())] = used[static_cast<std::size_t>(c)] = 1;
    part.dof_count = std::count(used.begin(), used.end(), 1);
    RequirePositiveSemiDefinite(part, out.dofs, options.psd_tolerance);
    step("checking the parts");
    out.parts.push_back(std::move(part));
  }
  // K_rest = K_nominal − Σ K_p (summed in the parts' order, as the script's sum()).
  Sparse sum(n, n);
  for (const FeImportedPart& p : out.parts) sum = Sparse(sum + p.stiffness);
  out.rest = k0.stiffness - sum;
  const double rest_limit = options.rest_tolerance * kmax;
  // Parts on their own elements: no DOF where the parts hold more than the whole model (a negative
  // diagonal of K_rest), which is two parts' runs changing the same elements, or a wrong scale.
  for (Eigen::Index c = 0; c < n; ++c) {
    const double d = out.rest.coeff(c, c);
    if (d < -rest_limit) {
      std::string holders;
      for (const FeImportedPart& p : out.parts)
        if (p.stiffness.coeff(c, c) != 0.0) holders += (holders.empty() ? "" : ", ") + p.name + " (" + p.source.string() + ")";
      throw InputError(nominal.stiffness.string() + ", row " + std::to_string(c + 1) + " (DOF " +
                           FeDofText(out.dofs[static_cast<std::size_t>(c)]) + ")",
                       "the parts overlap: their stiffness on this DOF's diagonal exceeds the nominal model's by " +
                           Relative(-d / kmax) + " of max |K| (K_rest = K_nominal - sum of parts is negative there); "
                           "parts holding it: " + holders +
                           ". Each part must be its own element set with its own material, and each run must change "
                           "only that part's modulus");
    }
  }
  if (pattern) {
    // K_rest on the other elements' DOF pairs (the script's check): what the parts leave where only
    // parts have elements is round-off, zeroed; more is a part whose run missed some of its elements.
    Eigen::Index i = -1, j = -1;
    const double off = pattern->ZeroOff(&out.rest, -1, out.dofs, &i, &j);
    out.rest_largest_dropped = off / kmax;
    if (off > rest_limit)
      throw InputError(nominal.stiffness.string() + ", row " + std::to_string(i + 1) + " (DOF " +
                           FeDofText(out.dofs[static_cast<std::size_t>(i)]) + ")",
                       "K_rest = K_nominal - sum of parts keeps " + Relative(off / kmax) + " of max |K| at (" +
                           FeDofText(out.dofs[static_cast<std::size_t>(i)]) + ", " +
                           FeDofText(out.dofs[static_cast<std::size_t>(j)]) +
                           "), where only parts' elements are (" + elements->file.string() +
                           "): a part's run did not change all of its elements, or its scale is not the one given");
  } else {
    // Without the deck: the round-off the parts leave on the entries they hold.
    double largest = 0.0;
    for (Eigen::Index c = 0; c < out.rest.outerSize(); ++c) {
      Sparse::InnerIterator q(sum, c);
      for (Sparse::InnerIterator it(out.rest, c); it; ++it) {
        while (q && q.row() < it.row()) ++q;
        if (q && q.row() == it.row() && std::abs(it.value()) <= rest_limit) {
          largest = std::max(largest, std::abs(it.value()));
          it.valueRef() = 0.0;
        }
      }
    }
    out.rest_largest_dropped = largest / kmax;
  }
  out.rest.prune(0.0);
  ReportProgress(progress, 1.0, "K_rest");
  return out;
}

std::vector<fs::path> FeImportOutputs(const FeImport& imported, const fs::path& toml) {
  const fs::path dir = toml.parent_path();
  std::vector<fs::path> out;
  if (imported.mass.size() > 0) out.push_back(dir / "M.mtx");
  out.push_back(dir / "K_rest.mtx");
  for (const FeImportedPart& p : imported.parts) out.push_back(dir / ("K_" + p.name + ".mtx"));
  out.push_back(dir / "dofs.csv");
  return out;
}

void WriteFeImport(const FeImport& imported, const fs::path& toml, const FeImportWriteOptions& options) {
  const fs::path dir = toml.parent_path();
  const auto quoted = [](const std::string& s) {
    std::string q = "\"";
    for (const char c : s) {
      if (c == '"' || c == '\\') q += '\\';
      q += c;
    }
    return q + "\"";
  };
  if (imported.mass.size() > 0) WriteMatrixMarket(dir / "M.mtx", imported.mass, true);
  WriteMatrixMarket(dir / "K_rest.mtx", imported.rest, true);
  for (const FeImportedPart& p : imported.parts) WriteMatrixMarket(dir / ("K_" + p.name + ".mtx"), p.stiffness, true);
  WriteFileAtomically(dir / "dofs.csv", [&](std::ostream& out) {
    out << "node,dof\n";
    for (const FeDof& d : imported.dofs) out << d.node << "," << d.direction << "\n";
  });
  std::ostringstream t;
  if (!options.comment.empty()) {
    std::istringstream lines(options.comment);
    for (std::string line; std::getline(lines, line);) t << "# " << line << "\n";
  }
  t << "[fe]\n";
  if (imported.mass.size() > 0) t << "mass = \"M.mtx\"\n";
  t << "stiffness = \"K_rest.mtx\"      # K_nominal - the parts\n";
  t << "dofs = \"dofs.csv\"\n";
  if (!options.nodes.empty()) t << "nodes = " << quoted(options.nodes) << "\n";
  for (const FeImportedPart& p : imported.parts) {
    t << "\n[[fe.part]]\nname = " << quoted(p.name) << "\n";
    if (!options.group.empty()) t << "group = " << quoted(options.group) << "\n";
    t << "stiffness = " << quoted("K_" + p.name + ".mtx") << "\n";
    if (options.uncertainty) {
      char u[32];
      const auto end = std::to_chars(u, u + sizeof u, *options.uncertainty).ptr;  // shortest round trip
      t << "uncertainty = " << std::string(u, end) << "\n";
    }
  }
  WriteTextFileAtomically(toml, t.str());
}

}  // namespace ema::formats
