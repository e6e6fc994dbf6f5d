// The model file (model-format.md) read with toml++; every error names file:line and the key.
#include "ema/formats/model_file.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <set>
#include <sstream>
#include <toml++/toml.h>
#include <Eigen/SparseCholesky>
#include <map>

#include "ema/core/error.hpp"
#include "ema/core/types.hpp"
#include "ema/formats/atomic_file.hpp"
#include "ema/formats/matrix_market.hpp"
#include "ema/formats/toml_fields.hpp"
#include "effect_fields.hpp"
#include "toml_text.hpp"
#include "text_lines.hpp"
#include "ema/formats/uff.hpp"
#include "ema/model/air_film.hpp"
#include "ema/model/effects.hpp"

namespace ema::formats {
namespace {

namespace fs = std::filesystem;
using model::Law;

// Calls `row` with the line number and the fields of every data line of a small CSV file (curve,
// DOF map, node list): blank and '#' lines skipped, ',' ';' and tabs read as blanks. Header
// lines are the caller's to recognise, since only it knows what a data row looks like.
void ForEachCsvRow(std::istream& in, const fs::path& file,
                   const std::function<void(int line, std::istringstream& fields)>& row) {
  std::string line;
  int no = 0;
  while (ReadTextLine(in, &line, file.string(), no + 1)) {
    ++no;
    if (line.find_first_not_of(" \t\r") == std::string::npos || line[0] == '#') continue;
    for (char& c : line)
      if (c == ',' || c == ';' || c == '\t') c = ' ';
    std::istringstream fields(line);
    row(no, fields);
  }
}

// The parameters an effect takes by name (model-format.md "Effects"); which of them a kind needs
// is ApplyEffect's question.
const std::set<std::string>& EffectParameterNames() {
  static const std::set<std::string> names = {"factor", "value", "mass", "k"};
  return names;
}

class Reader : public TomlFields {
 public:
  explicit Reader(const fs::path& path) : TomlFields(path.string()), path_(path), dir_(path.parent_path()) {}
  /// For TOML values inside another format: `place` names them in messages (their lines are in no
  /// file), `dir` resolves relative paths.
  Reader(const std::string& place, const fs::path& dir) : TomlFields(place, TomlLines::kInNoFile), dir_(dir) {}

  int Line(const toml::node& n) const { return static_cast<int>(n.source().begin.line); }


  const toml::node& Require(const toml::table& t, const std::string& key, const std::string& context) const {
    const toml::node* n = t.get(key);
    if (!n) throw InputError(At(t), context + ": missing key '" + key + "'");
    return *n;
  }

  double Number(const toml::node& n, const std::string& key) const {
    if (auto v = n.value<double>(); v && (n.is_floating_point() || n.is_integer())) return *v;
    throw InputError(At(n), "key '" + key + "': expected a number");
  }
  std::optional<double> OptNumber(const toml::table& t, const std::string& key) const {
    const toml::node* n = t.get(key);
    if (!n) return std::nullopt;
    return Number(*n, key);
  }
  double NumberOr(const toml::table& t, const std::string& key, double fallback) const {
    return OptNumber(t, key).value_or(fallback);
  }
  std::string String(const toml::node& n, const std::string& key) const {
    if (auto v = n.value<std::string>(); v && n.is_string()) return *v;
    throw InputError(At(n), "key '" + key + "': expected a string");
  }
  std::vector<double> Numbers(const toml::node& n, const std::string& key) const {
    const toml::array* a = n.as_array();
    if (!a) throw InputError(At(n), "key '" + key + "': expected an array of numbers");
    std::vector<double> out;
    for (const toml::node& e : *a) out.push_back(Number(e, key));
    return out;
  }
  Eigen::Vector3d Vector3(const toml::node& n, const std::string& key) const {
    const std::vector<double> v = Numbers(n, key);
    if (v.size() != 3) throw InputError(At(n), "key '" + key + "': expected 3 numbers [x, y, z], found " + std::to_string(v.size()));
    return {v[0], v[1], v[2]};
  }
  const toml::table& Table(const toml::node& n, const std::string& key) const {
    const toml::table* t = n.as_table();
    if (!t) throw InputError(At(n), "key '" + key + "': expected a table");
    return *t;
  }
  /// A relative 1σ (model-format.md "Prior knowledge"): a number > 0.
  double Uncertainty(const toml::node& n, const std::string& context) const {
    const double v = Number(n, "uncertainty");
    if (!(v > 0.0) || !std::isfinite(v))
      throw InputError(At(n), context + ": uncertainty must be a relative 1σ > 0 (0.02 = 2 %), found " + std::to_string(v));
    return v;
  }
  fs::path Resolve(const std::string& p) const {
    fs::path f(p);
    return f.is_relative() ? dir_ / f : f;
  }

  /// Two-column CSV (optional header line): x,y.
  void ReadCurve(const toml::node& n, std::vector<double>* x, std::vector<double>* y) const {
    const fs::path f = Resolve(String(n, "file"));
    std::ifstream in(f);
    if (!in) throw InputError(At(n), "cannot open curve file '" + f.string() + "'");
    try {
      ForEachCsvRow(in, f, [&](int no, std::istringstream& s) {
        double a = 0, b = 0;
        if (!(s >> a >> b)) {
          if (x->empty()) return;  // header line(s) before the data
          throw InputError(f.string() + ":" + std::to_string(no), "expected two numbers 'x,y'");
        }
        x->push_back(a);
        y->push_back(b);
      });
    } catch (const InputError& e) {
      if (lines_ == TomlLines::kOfTheFile) throw;
      // A law with no file line of its own (DIAG.json's): the curve file's place follows the
      // place of the value that names it ("DIAG.json: candidate rank 3: effect 1: curve.csv:4: ...").
      throw InputError(file_, e.what());
    }
  }

  Law ParseLaw(const toml::node& node, const std::string& context) const {
    const toml::table& t = Table(node, context);
    static const std::set<std::string> kKinds = {"linear", "table", "air_film", "hertz", "series", "micro_slip"};
    if (t.size() != 1)
      throw InputError(At(node), context +
                                     ": a law is a table with exactly one of linear, table, air_film, hertz, series, micro_slip");
    const auto first = t.begin();
    const std::string kind(first->first.str());
    const toml::node& body_node = first->second;
    if (!kKinds.count(kind))
      throw InputError(At(body_node), context + ": unknown law '" + kind + "' (allowed: air_film, hertz, linear, series, table)");
    const toml::table& b = Table(body_node, kind);
    const std::string ctx = context + " law " + kind;
    if (kind == "linear") {
      CheckKeys(b, {"k"}, ctx);
      return model::LinearLaw{Number(Require(b, "k", ctx), "k")};
    }
    if (kind == "table") {
      CheckKeys(b, {"deflection", "force", "file", "operating_deflection", "operating_force"}, ctx);
      model::TableLaw law;
      if (const auto* f = b.get("file")) ReadCurve(*f, &law.deflection, &law.force);
      for (const char* key : {"deflection", "force"}) {
        const toml::node* n = b.get(key);
        if (!n) continue;
        const bool is_deflection = std::string(key) == "deflection";
        if (n->is_array()) {
          (is_deflection ? law.deflection : law.force) = Numbers(*n, key);
        } else {
          (is_deflection ? law.operating_deflection : law.operating_force) = Number(*n, key);
        }
      }
      if (auto v = OptNumber(b, "operating_deflection")) law.operating_deflection = v;
      if (auto v = OptNumber(b, "operating_force")) law.operating_force = v;
      if (law.deflection.empty()) throw InputError(At(body_node), ctx + ": needs deflection = [..] and force = [..] or file");
      return law;
    }
    if (kind == "air_film") {
      CheckKeys(b, {"gap", "load", "file", "operating_gap", "pad"}, ctx);
      model::AirFilmLaw law;
      if (const auto* f = b.get("file")) ReadCurve(*f, &law.gap, &law.load);
      if (const auto* pad_node = b.get("pad")) {
        // Load-lift curve from pad geometry (thesis section 6.2.1, docs/model.md).
        const toml::table& p = Table(*pad_node, "pad");
        CheckKeys(p, {"diameter", "thickness", "permeability", "supply_pressure", "ambient_pressure", "gap_min",
                      "gap_max", "points"},
                  ctx + " pad");
        model::PorousPad pad;
        pad.diameter = Number(Require(p, "diameter", ctx + " pad"), "diameter");
        pad.thickness = Number(Require(p, "thickness", ctx + " pad"), "thickness");
        pad.permeability = Number(Require(p, "permeability", ctx + " pad"), "permeability");
        pad.supply_pressure = Number(Require(p, "supply_pressure", ctx + " pad"), "supply_pressure");
        pad.ambient_pressure = NumberOr(p, "ambient_pressure", pad.ambient_pressure);
        pad.gap_min = NumberOr(p, "gap_min", pad.gap_min);
        pad.gap_max = NumberOr(p, "gap_max", pad.gap_max);
        pad.points = static_cast<int>(NumberOr(p, "points", pad.points));
        try {
          law = model::PorousPadCurve(pad, 0.0);
        } catch (const InputError& e) {
          throw InputError(At(*pad_node), e.what());
        }
      }
      if (const auto* g = b.get("gap")) {
        if (g->is_array()) law.gap = Numbers(*g, "gap");
        else law.operating_gap = Number(*g, "gap");
      }
      if (const auto* l = b.get("load")) law.load = Numbers(*l, "load");
      if (auto v = OptNumber(b, "operating_gap")) law.operating_gap = *v;
      if (law.gap.empty()) throw InputError(At(body_node), ctx + ": needs gap = [..] and load = [..] or file");
      return law;
    }
    if (kind == "hertz") {
      CheckKeys(b, {"modulus", "radius", "offset", "deflection", "force", "preload"}, ctx);
      model::HertzLaw law;
      law.modulus = Number(Require(b, "modulus", ctx), "modulus");
      law.radius = Number(Require(b, "radius", ctx), "radius");
      law.offset = NumberOr(b, "offset", 0.0);
      law.operating_deflection = OptNumber(b, "deflection");
      law.operating_force = OptNumber(b, "force");
      if (auto p = OptNumber(b, "preload")) law.operating_force = p;
      return law;
    }
    if (kind == "micro_slip") {
      CheckKeys(b, {"k", "slip_force", "elements"}, ctx);
      model::MicroSlipLaw law;
      law.k = Number(Require(b, "k", ctx), "k");
      law.slip_force = Number(Require(b, "slip_force", ctx), "slip_force");
      if (const toml::node* e = b.get("elements")) {
        const auto v = IntValue(*e);
        if (!v || *v < 1) throw InputError(At(*e), ctx + ": 'elements' must be a positive integer");
        law.elements = *v;
      }
      return law;
    }
    CheckKeys(b, {"elements", "setting", "force"}, ctx);
    model::SeriesLaw law;
    const toml::array* elements = Require(b, "elements", ctx).as_array();
    if (!elements || elements->empty()) throw InputError(At(body_node), ctx + ": 'elements' must be a non-empty array of laws");
    int i = 0;
    for (const toml::node& e : *elements) law.elements.push_back(ParseLaw(e, ctx + " element " + std::to_string(++i)));
    law.setting = NumberOr(b, "setting", 0.0);
    law.force = OptNumber(b, "force");
    return law;
  }

  model::Anchor ParseAnchor(const toml::node& node, const std::string& context) const {
    const toml::table& t = Table(node, context);
    CheckKeys(t, {"body", "at", "node"}, context);
    return AnchorFrom(t, context, true);
  }

  /// body + at, or node (used by spring ends, masses and points).
  model::Anchor AnchorFrom(const toml::table& t, const std::string& context, bool allow_ground) const {
    model::Anchor a;
    const toml::node* body = t.get("body");
    const toml::node* node = t.get("node");
    if (body && node) throw InputError(At(t), context + ": give either 'body' or 'node', not both");
    if (node) {
      const auto id = IntValue(*node);
      if (!id || *id <= 0) throw InputError(At(*node), context + ": 'node' must be a positive integer");
      a.node = *id;
      return a;
    }
    if (!body) throw InputError(At(t), context + ": missing key 'body' (or 'node')");
    a.body = String(*body, "body");
    if (!allow_ground && a.body == model::kGround) throw InputError(At(*body), context + ": cannot be on ground");
    if (const toml::node* at = t.get("at")) {
      a.at = Vector3(*at, "at");
      a.has_at = true;
    }
    return a;
  }

  // An [fe] or [[fe.part]] matrix file: it exists, reads as Matrix Market and is symmetric.
  Eigen::SparseMatrix<double> FeMatrix(const toml::table& t, const char* key, const std::string& context,
                                       std::string* file) const {
    const toml::node& n = *t.get(key);
    const fs::path f = Resolve(String(n, key));
    std::error_code ec;  // an unusable name (too long, ...) is "not found", not a filesystem_error
    if (!fs::exists(f, ec)) throw InputError(At(n), context + " " + key + ": file '" + f.string() + "' not found");
    Eigen::SparseMatrix<double> a = ReadMatrixMarket(f);
    RequireSymmetric(a, f);
    *file = f.string();
    return a;
  }

  void ReadFe(const toml::table& t, model::Model* m) const {
    CheckKeys(t, {"mass", "stiffness", "dofs", "nodes", "part"}, "[fe]");
    const toml::node* parts = t.get("part");
    // With parts, [fe].mass and [fe].stiffness are optional: the parts may carry all of it.
    if (!parts) {
      Require(t, "mass", "[fe]");
      Require(t, "stiffness", "[fe]");
    }
    const fs::path dofs = Resolve(String(Require(t, "dofs", "[fe]"), "dofs"));
    {
      std::error_code ec;
      if (!fs::exists(dofs, ec)) throw InputError(At(*t.get("dofs")), "[fe] dofs: file '" + dofs.string() + "' not found");
    }
    if (t.get("mass")) m->fe.mass = FeMatrix(t, "mass", "[fe]", &m->fe.mass_file);
    if (t.get("stiffness")) m->fe.stiffness = FeMatrix(t, "stiffness", "[fe]", &m->fe.stiffness_file);
    m->fe.origin = dofs.string();
    // DOF map: node,dof per matrix row.
    std::ifstream in(dofs);
    if (!in) throw InputError(At(*t.get("dofs")), "cannot open DOF map '" + dofs.string() + "'");
    ForEachCsvRow(in, dofs, [&](int no, std::istringstream& s) {
      long node = 0;
      std::string dof;
      if (!(s >> node >> dof)) {
        if (no == 1) return;  // header
        throw InputError(dofs.string() + ":" + std::to_string(no), "expected 'node,dof'");
      }
      int code = 0;
      static const char* kNames[] = {"ux", "uy", "uz", "rx", "ry", "rz"};
      for (int i = 0; i < 6; ++i)
        if (dof == kNames[i] || dof == std::to_string(i + 1)) code = i + 1;
      if (code == 0) {
        if (no == 1 && m->fe.dofs.empty()) return;  // header such as "node,dof"
        throw InputError(dofs.string() + ":" + std::to_string(no), "dof must be 1..6 or ux..rz, found '" + dof + "'");
      }
      m->fe.dofs.push_back({static_cast<int>(node), code});
    });
    const auto rows = static_cast<Eigen::Index>(m->fe.dofs.size());
    if (m->fe.mass.rows() > 0 && m->fe.mass.rows() != rows)
      throw InputError(dofs.string(), "DOF map has " + std::to_string(rows) + " rows but " + m->fe.mass_file +
                                          " has " + std::to_string(m->fe.mass.rows()) + " rows");
    if (m->fe.stiffness.rows() > 0 && m->fe.mass.rows() > 0 && m->fe.mass.rows() != m->fe.stiffness.rows())
      throw InputError(m->fe.stiffness_file, "stiffness matrix has " + std::to_string(m->fe.stiffness.rows()) +
                                                 " rows but the mass matrix has " + std::to_string(m->fe.mass.rows()));
    if (m->fe.stiffness.rows() > 0 && m->fe.stiffness.rows() != rows)
      throw InputError(dofs.string(), "DOF map has " + std::to_string(rows) + " rows but " + m->fe.stiffness_file +
                                          " has " + std::to_string(m->fe.stiffness.rows()) + " rows");
    if (parts) ReadParts(*parts, m);
    if (const toml::node* nodes = t.get("nodes")) ReadNodes(Resolve(String(*nodes, "nodes")), *nodes, m);
  }

  // [[fe.part]] blocks (model-format.md "FE models built from parts").
  void ReadParts(const toml::node& node, model::Model* m) const {
    const toml::array* list = node.as_array();
    if (!list) throw InputError(At(node), "'fe.part' must be an array of tables: [[fe.part]]");
    const auto rows = static_cast<Eigen::Index>(m->fe.dofs.size());
    // Part groups and parts in no group share one namespace with spring groups and bodies.
    std::set<std::string> spring_groups, bodies, part_names;
    for (const auto& s : m->springs) spring_groups.insert(s.group);
    for (const auto& b : m->bodies) bodies.insert(b.name);
    std::map<std::string, int> targets;  // group or lone part name -> line
    for (const toml::node& e : *list) {
      const toml::table& t = Table(e, "fe.part");
      CheckKeys(t, {"name", "group", "stiffness", "mass", "uncertainty"}, "[[fe.part]]");
      model::FePart p;
      p.line = Line(t);
      p.name = String(Require(t, "name", "[[fe.part]]"), "name");
      const std::string ctx = "part '" + p.name + "'";
      if (p.name.empty() || p.name.find('/') != std::string::npos || p.name.find('+') != std::string::npos ||
          p.name == "*")
        throw InputError(At(*t.get("name")),
                         "[[fe.part]]: name must be a non-empty name without '/' or '+', and not '*'");
      if (!part_names.insert(p.name).second) throw InputError(At(t), "[[fe.part]]: duplicate part name '" + p.name + "'");
      if (const toml::node* g = t.get("group")) {
        p.group = String(*g, "group");
        if (p.group.empty() || p.group.find('/') != std::string::npos || p.group.find('+') != std::string::npos)
          throw InputError(At(*g), ctx + ": group must be a non-empty name without '/' or '+'");
      }
      const std::string target = p.group.empty() ? p.name : p.group;
      const char* what = p.group.empty() ? "part" : "part group";
      if (spring_groups.count(target))
        throw InputError(At(t), ctx + ": " + what + " name '" + target +
                                    "' is also a spring group; part groups, parts in no group, spring groups and bodies "
                                    "share one namespace (model-format.md)");
      if (bodies.count(target))
        throw InputError(At(t), ctx + ": " + what + " name '" + target + "' is also a body; part groups, parts in no "
                                    "group, spring groups and bodies share one namespace (model-format.md)");
      if (const auto it = targets.find(target); it != targets.end() && (p.group.empty() || it->second < 0))
        throw InputError(At(t), ctx + ": name '" + target + "' is already used by another part or part group");
      targets[target] = p.group.empty() ? -p.line : p.line;
      if (!t.get("stiffness") && !t.get("mass"))
        throw InputError(At(t), ctx + ": expected 'stiffness' (and optionally 'mass'): the part's own matrices");
      for (const char* key : {"stiffness", "mass"}) {
        if (!t.get(key)) continue;
        const bool is_stiffness = std::string(key) == "stiffness";
        std::string& file = is_stiffness ? p.stiffness_file : p.mass_file;
        auto matrix = std::make_shared<const Eigen::SparseMatrix<double>>(FeMatrix(t, key, "[[fe.part]] " + p.name, &file));
        const Eigen::SparseMatrix<double>* a = matrix.get();
        (is_stiffness ? p.stiffness : p.mass) = matrix;
        if (a->rows() != rows)
          throw InputError(At(t), ctx + ": " + file + " is " + std::to_string(a->rows()) + "x" + std::to_string(a->cols()) +
                                      " but the [fe] DOF map has " + std::to_string(rows) + " rows: expected a " +
                                      std::to_string(rows) + "x" + std::to_string(rows) +
                                      " matrix in the DOF map's order (the part's contribution to the global matrix)");
        RequirePositiveSemiDefinite(*a, m->fe, At(t) + ": " + ctx + " (" + file + ")", key);
      }
      if (const toml::node* u = t.get("uncertainty")) p.uncertainty = Uncertainty(*u, ctx);
      m->fe.parts.push_back(std::move(p));
    }
  }

  // A part's matrix is a sum of element matrices, each positive semi-definite
  // (model::FirstNegativePivotRow); a negative pivot names the DOF.
  static void RequirePositiveSemiDefinite(const Eigen::SparseMatrix<double>& a, const model::FeMatrices& fe,
                                          const std::string& where, const char* what) {
    const int row = model::FirstNegativePivotRow(a);
    if (row < 0) return;
    static const char* kDofNames[] = {"ux", "uy", "uz", "rx", "ry", "rz"};
    const auto& dof = fe.dofs[static_cast<std::size_t>(row)];
    throw InputError(where, std::string("the part's ") + what + " is not positive semi-definite (a negative pivot at node " +
                                std::to_string(dof.node) + " " + kDofNames[std::clamp(dof.dof, 1, 6) - 1] +
                                ", matrix row " + std::to_string(row + 1) +
                                "): expected the sum of the part's element matrices, which adds no negative " +
                                "stiffness or mass; with the part, K could be indefinite");
  }

  /// nodes.csv (node,x,y,z) or a UFF file with dataset 15 or 2411 (read with the UFF reader).
  void ReadNodes(const fs::path& f, const toml::node& key, model::Model* m) const {
    std::ifstream in(f);
    if (!in) throw InputError(At(key), "cannot open nodes file '" + f.string() + "'");
    if (uff::LooksLikeUff(f)) {
      uff::Reader reader(f);
      uff::Dataset d;
      while (reader.Next(&d)) {
        const std::vector<uff::NodeRecord>* nodes = nullptr;
        if (const auto* n15 = std::get_if<uff::Nodes15>(&d.body)) nodes = &n15->nodes;
        if (const auto* n2411 = std::get_if<uff::Nodes2411>(&d.body)) nodes = &n2411->nodes;
        if (!nodes) continue;
        for (const uff::NodeRecord& n : *nodes)
          m->fe.node_positions[static_cast<int>(n.label)] = {n.xyz[0], n.xyz[1], n.xyz[2]};
      }
      return;
    }
    ForEachCsvRow(in, f, [&](int no, std::istringstream& s) {
      long id;
      double x, y, z;
      if (!(s >> id >> x >> y >> z)) {
        if (no == 1) return;  // header
        throw InputError(f.string() + ":" + std::to_string(no), "expected 'node,x,y,z'");
      }
      m->fe.node_positions[static_cast<int>(id)] = {x, y, z};
    });
  }

  model::Model Read() const {
    toml::table root;
    try {
      root = toml::parse_file(path_.string());
    } catch (const toml::parse_error& e) {
      throw InputError(file_ + ":" + std::to_string(e.source().begin.line), std::string(e.description()));
    }
    model::Model m;
    m.origin = file_;
    CheckKeys(root, {"model", "body", "mass", "spring", "damping", "point", "fe", "setup", "effect", "priors"},
              "the model file");
    if (const toml::node* n = root.get("priors")) {
      const toml::table& t = Table(*n, "priors");
      std::set<std::string> keys(model::EffectKinds().begin(), model::EffectKinds().end());
      keys.insert({"stiffness_fault_share", "stiffness_fault_width"});
      CheckKeys(t, keys, "[priors]");
      for (const auto& [k, v] : t) {
        const std::string key(k.str());
        if (key == "stiffness_fault_share") {
          // The prior weight of a grossly-off stiffness (loose, cracked): a share in [0, 1).
          if (!v.is_number() || !(*v.value<double>() >= 0.0 && *v.value<double>() < 1.0))
            throw InputError(At(v), "[priors] stiffness_fault_share: expected a share in [0, 1) (0.02 = 2 %; 0: no fault "
                                    "tail, the plain log-normal)");
          m.stiffness_fault_share = *v.value<double>();
        } else if (key == "stiffness_fault_width") {
          if (!v.is_number() || !(*v.value<double>() > 0.0) || !std::isfinite(*v.value<double>()))
            throw InputError(At(v), "[priors] stiffness_fault_width: expected the tail's 1σ of ln(factor), a number > 0 "
                                    "(3.0: a factor anywhere within about ×/÷ 400)");
          m.stiffness_fault_width = *v.value<double>();
        } else {
          m.priors[model::FindEffectKind(key)->kind] = Uncertainty(v, "[priors] " + key);  // a kind: CheckKeys said so
        }
      }
    }
    if (const toml::node* n = root.get("model")) {
      const toml::table& t = Table(*n, "model");
      CheckKeys(t, {"name", "description"}, "[model]");
      if (const toml::node* name = t.get("name")) m.name = String(*name, "name");
    }
    auto each = [&](const char* key, auto&& fn) {
      const toml::node* n = root.get(key);
      if (!n) return;
      const toml::array* a = n->as_array();
      if (!a) throw InputError(At(*n), std::string("'") + key + "' must be an array of tables: [[" + key + "]]");
      for (const toml::node& e : *a) fn(Table(e, key));
    };
    std::set<std::string> names;
    each("body", [&](const toml::table& t) {
      CheckKeys(t, {"name", "mass", "inertia", "products", "centre", "uncertainty"}, "[[body]]");
      model::Body b;
      b.line = Line(t);
      b.name = String(Require(t, "name", "[[body]]"), "name");
      if (b.name == model::kGround) throw InputError(At(t), "[[body]]: 'ground' is a reserved body name");
      if (b.name.find('/') != std::string::npos)
        throw InputError(At(*t.get("name")), "[[body]]: name '" + b.name +
                                                 "' has a '/': expected a name without it "
                                                 "('/' separates a group from its member in an effect's target)");
      if (!names.insert(b.name).second) throw InputError(At(t), "[[body]]: duplicate body name '" + b.name + "'");
      b.mass = Number(Require(t, "mass", "[[body]] " + b.name), "mass");
      if (!(b.mass > 0.0)) throw InputError(At(*t.get("mass")), "body '" + b.name + "': mass must be > 0");
      b.inertia = Vector3(Require(t, "inertia", "[[body]] " + b.name), "inertia");
      if (const toml::node* p = t.get("products")) b.products = Vector3(*p, "products");
      if (const toml::node* c = t.get("centre")) b.centre = Vector3(*c, "centre");
      if (const toml::node* u = t.get("uncertainty")) b.uncertainty = Uncertainty(*u, "body '" + b.name + "'");
      m.bodies.push_back(b);
    });
    auto check_body = [&](const model::Anchor& a, const toml::table& t, const std::string& what) {
      if (!a.IsNode() && !a.IsGround() && !names.count(a.body)) {
        std::string known;
        for (const auto& n : names) known += n + ", ";
        throw InputError(At(t), what + ": unknown body '" + a.body + "' (known: " + known + "ground)");
      }
    };
    each("mass", [&](const toml::table& t) {
      CheckKeys(t, {"name", "body", "node", "at", "mass"}, "[[mass]]");
      model::PointMass pm;
      pm.line = Line(t);
      if (const toml::node* n = t.get("name")) pm.name = String(*n, "name");
      pm.where = AnchorFrom(t, "[[mass]] " + pm.name, false);
      check_body(pm.where, t, "mass '" + pm.name + "'");
      pm.mass = Number(Require(t, "mass", "[[mass]] " + pm.name), "mass");
      if (!(pm.mass >= 0.0)) throw InputError(At(t), "mass '" + pm.name + "': mass must be >= 0");
      m.masses.push_back(pm);
    });
    each("spring", [&](const toml::table& t) {
      CheckKeys(t, {"name", "group", "member", "kind", "a", "b", "direction", "law", "uncertainty"}, "[[spring]]");
      model::Spring s;
      s.line = Line(t);
      s.name = String(Require(t, "name", "[[spring]]"), "name");
      const std::string ctx = "spring '" + s.name + "'";
      s.group = t.get("group") ? String(*t.get("group"), "group") : s.name;
      if (s.group.find('/') != std::string::npos) {
        const toml::node* group = t.get("group");
        const std::string what = group ? ": group must be a name without '/'"
                                       : ": a spring without 'group' is a group of its own, named after it, and a "
                                         "group's name has no '/': give it a group";
        throw InputError(At(group ? *group : *t.get("name")),
                         ctx + what + " ('/' separates a group from its member in an effect's target)");
      }
      if (const toml::node* mem = t.get("member")) {
        s.member = String(*mem, "member");
        if (s.member.empty() || s.member.find('/') != std::string::npos || s.member == "*")
          throw InputError(At(*mem), ctx + ": member must be a non-empty name without '/', and not '*'");
      }
      if (const toml::node* u = t.get("uncertainty")) s.uncertainty = Uncertainty(*u, ctx);
      if (const toml::node* k = t.get("kind")) {
        const std::string kind = String(*k, "kind");
        if (kind == "rotational") s.kind = model::Spring::Kind::kRotational;
        else if (kind != "translational")
          throw InputError(At(*k), ctx + ": kind must be 'translational' or 'rotational', found '" + kind + "'");
      }
      s.a = ParseAnchor(Require(t, "a", ctx), ctx + " end a");
      check_body(s.a, t, ctx + " end a");
      if (const toml::node* b = t.get("b")) {
        s.b = ParseAnchor(*b, ctx + " end b");
        check_body(s.b, t, ctx + " end b");
      } else {
        s.b.body = model::kGround;
      }
      if (s.a.IsNode() ? s.a.node == s.b.node : (!s.b.IsNode() && s.a.body == s.b.body))
        throw InputError(At(t.get("b") ? *t.get("b") : t), ctx + ": both ends are on " +
                                                              (s.a.IsNode() ? "FE node " + std::to_string(s.a.node)
                                                                            : "'" + s.a.body + "'") +
                                                              ": expected a spring between two different bodies, nodes or ground");
      const toml::node& dir = Require(t, "direction", ctx);
      if (dir.is_string()) {
        const int code = ParseDirection(String(dir, "direction"));
        if (code == 0 || std::abs(code) > 3) throw InputError(At(dir), ctx + ": direction must be [x, y, z] or +X/-Y/...");
        s.direction = Eigen::Vector3d::Unit(std::abs(code) - 1) * (code < 0 ? -1.0 : 1.0);
      } else {
        s.direction = Vector3(dir, "direction");
      }
      if (!(s.direction.norm() > 0.0)) throw InputError(At(dir), ctx + ": direction must not be the zero vector");
      s.law = ParseLaw(Require(t, "law", ctx), ctx);
      m.springs.push_back(std::move(s));
    });
    if (const toml::node* n = root.get("damping")) {
      const toml::table& t = Table(*n, "damping");
      CheckKeys(t, {"ratio", "ratios"}, "[damping]");
      m.damping.ratio = NumberOr(t, "ratio", 0.0);
      if (const toml::node* r = t.get("ratios")) m.damping.ratios = Numbers(*r, "ratios");
      for (double r : m.damping.ratios)
        if (!(r >= 0.0 && r < 1.0)) throw InputError(At(t), "[damping]: ratios must lie in [0, 1)");
      if (!(m.damping.ratio >= 0.0 && m.damping.ratio < 1.0)) throw InputError(At(t), "[damping]: ratio must lie in [0, 1)");
    }
    std::set<int> ids;
    each("point", [&](const toml::table& t) {
      CheckKeys(t, {"id", "body", "node", "at"}, "[[point]]");
      model::TestPoint p;
      p.line = Line(t);
      const toml::node& id = Require(t, "id", "[[point]]");
      const auto id_value = IntValue(id);
      if (!id_value || *id_value <= 0) throw InputError(At(id), "[[point]]: id must be a positive integer");
      p.id = *id_value;
      if (!ids.insert(p.id).second) throw InputError(At(t), "[[point]]: id " + std::to_string(p.id) + " appears twice");
      p.where = AnchorFrom(t, "point " + std::to_string(p.id), true);
      check_body(p.where, t, "point " + std::to_string(p.id));
      m.points.push_back(p);
    });
    if (const toml::node* n = root.get("fe")) ReadFe(Table(*n, "fe"), &m);
    each("setup", [&](const toml::table& t) {
      CheckKeys(t, {"name", "operating", "description"}, "[[setup]]");
      model::Setup s;
      s.line = Line(t);
      s.name = String(Require(t, "name", "[[setup]]"), "name");
      if (const toml::node* o = t.get("operating"))
        for (const auto& [k, v] : Table(*o, "operating")) s.operating[std::string(k.str())] = Number(v, std::string(k.str()));
      m.setups.push_back(s);
    });
    each("effect", [&](const toml::table& t) { m.effects.push_back(ReadEffect(t)); });
    return m;
  }

  /// One [[effect]] table: kind, target, the parameters factor/value/mass/k and the law.
  model::Effect ReadEffect(const toml::table& t) const {
    std::set<std::string> keys = EffectParameterNames();
    keys.insert({"kind", "target", "law"});
    CheckKeys(t, keys, "[[effect]]");
    const std::string kind = String(Require(t, "kind", "[[effect]]"), "kind");
    const toml::node& target_node = Require(t, "target", "[[effect]]");
    const std::string target = String(target_node, "target");
    std::map<std::string, double> parameters;
    for (const std::string& name : EffectParameterNames())
      if (auto v = OptNumber(t, name)) parameters[name] = *v;
    model::Effect e = EffectOf(kind, target, parameters, t.get("law"), At(t), At(target_node));
    e.line = Line(t);
    return e;
  }

  /// An effect from its fields read as values (an [[effect]] table's, or DIAG.json's: effect_fields.hpp):
  /// its rules past the types of the values. The kind and the target are said at `kind_at` and
  /// `target_at`, the law's nodes at their own places (At).
  model::Effect EffectOf(const std::string& kind, const std::string& target,
                         const std::map<std::string, double>& parameters, const toml::node* law,
                         const std::string& kind_at, const std::string& target_at) const {
    model::Effect e;
    for (const auto& [name, value] : parameters) {
      if (!EffectParameterNames().count(name)) {
        std::string allowed;
        for (const std::string& p : EffectParameterNames()) allowed += (allowed.empty() ? "" : ", ") + p;
        throw InputError(kind_at, "effect " + kind + " '" + target + "': unknown parameter '" + name +
                                      "' (allowed: " + allowed + ")");
      }
      e.parameters[name] = value;
    }
    if (law) e.law = ParseLaw(*law, "effect " + kind);
    // The one place an effect's kind and target are read from text (DIAG.json's effects come
    // through here too).
    const model::EffectKindInfo* info = model::FindEffectKind(kind);
    if (!info) {
      std::string kinds;
      for (const std::string& k : model::EffectKinds()) kinds += (kinds.empty() ? "" : ", ") + k;
      throw InputError(kind_at, "effect " + kind + " '" + target + "': unknown effect kind (allowed: " + kinds + ")");
    }
    e.kind = info->kind;
    std::string why;
    std::optional<model::EffectTarget> parsed = model::ParseEffectTarget(e.kind, target, &why);
    if (!parsed) throw InputError(target_at, "effect " + kind + " '" + target + "': " + why);
    e.target = std::move(*parsed);
    return e;
  }

 private:
  fs::path path_;
  fs::path dir_;
};

std::string Num(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  std::string s(buf);
  if (s.find_first_of(".eEni") == std::string::npos) s += ".0";
  return s;
}

std::string Array(const std::vector<double>& v) {
  std::string s = "[";
  for (std::size_t i = 0; i < v.size(); ++i) s += (i ? ", " : "") + Num(v[i]);
  return s + "]";
}

}  // namespace

model::Effect EffectFromFields(const std::string& kind, const std::string& target,
                               const std::map<std::string, double>& parameters, const toml::node* law,
                               const std::string& place, const std::filesystem::path& base_dir) {
  return Reader(place, base_dir).EffectOf(kind, target, parameters, law, place, place);
}

model::Model ReadModelFile(const std::filesystem::path& path) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) throw InputError(path.string(), "model file not found");
  return Reader(path).Read();
}

std::string LawToToml(const model::Law& law) {
  std::string body;
  if (const auto* l = std::get_if<model::LinearLaw>(&law.value)) {
    body = "k = " + Num(l->k);
  } else if (const auto* t = std::get_if<model::TableLaw>(&law.value)) {
    body = "deflection = " + Array(t->deflection) + ", force = " + Array(t->force);
    if (t->operating_deflection) body += ", operating_deflection = " + Num(*t->operating_deflection);
    if (t->operating_force) body += ", operating_force = " + Num(*t->operating_force);
  } else if (const auto* a = std::get_if<model::AirFilmLaw>(&law.value)) {
    body = "gap = " + Array(a->gap) + ", load = " + Array(a->load) + ", operating_gap = " + Num(a->operating_gap);
  } else if (const auto* h = std::get_if<model::HertzLaw>(&law.value)) {
    body = "modulus = " + Num(h->modulus) + ", radius = " + Num(h->radius) + ", offset = " + Num(h->offset);
    if (h->operating_deflection) body += ", deflection = " + Num(*h->operating_deflection);
    if (h->operating_force) body += ", force = " + Num(*h->operating_force);
  } else if (const auto* m = std::get_if<model::MicroSlipLaw>(&law.value)) {
    body = "k = " + Num(m->k) + ", slip_force = " + Num(m->slip_force) + ", elements = " + std::to_string(m->elements);
  } else {
    const auto& s = std::get<model::SeriesLaw>(law.value);
    body = "elements = [";
    for (std::size_t i = 0; i < s.elements.size(); ++i) body += (i ? ", " : "") + LawToToml(s.elements[i]);
    body += "], setting = " + Num(s.setting);
    if (s.force) body += ", force = " + Num(*s.force);
  }
  return "{ " + law.KindName() + " = { " + body + " } }";
}

std::string EffectToToml(const model::Effect& e) {
  std::string s = "[[effect]]\nkind = " + TomlString(model::KindName(e.kind)) +
                  "\ntarget = " + TomlString(model::TargetText(e.target)) + "\n";
  const bool k_as_law = e.kind == model::EffectKind::kSeriesCompliance && !e.law && e.parameters.count("k");
  for (const auto& [k, v] : e.parameters)
    if (!(k_as_law && k == "k")) s += k + " = " + Num(v) + "\n";
  if (e.law) s += "law = " + LawToToml(*e.law) + "\n";
  if (k_as_law) s += "law = " + LawToToml(model::LinearLaw{e.parameters.at("k")}) + "\n";
  return s;
}

namespace {

// The string literal starting at (line, column) of `text` (1-based, as toml++ reports a value's
// source): [first, last) byte offsets including the quotes; npos when none is found.
std::pair<size_t, size_t> LiteralAt(const std::string& text, size_t line, size_t column) {
  size_t pos = 0;
  for (size_t l = 1; l < line && pos != std::string::npos; ++l) {
    pos = text.find('\n', pos);
    if (pos != std::string::npos) ++pos;
  }
  if (pos == std::string::npos) return {std::string::npos, 0};
  size_t i = pos + (column > 0 ? column - 1 : 0);
  while (i < text.size() && text[i] != '"' && text[i] != '\'' && text[i] != '\n') ++i;
  if (i >= text.size() || text[i] == '\n') return {std::string::npos, 0};
  const char quote = text[i];
  if (text.compare(i, 3, std::string(3, quote)) == 0) return {std::string::npos, 0};  // multi-line: left alone
  for (size_t j = i + 1; j < text.size() && text[j] != '\n'; ++j) {
    if (quote == '"' && text[j] == '\\') {
      ++j;
      continue;
    }
    if (text[j] == quote) return {i, j + 1};
  }
  return {std::string::npos, 0};
}

// Every path-valued string of a model file: `file =` of laws (anywhere), [fe] and [[fe.part]] files.
void CollectPaths(const toml::node& node, bool fe, std::vector<const toml::node*>* out) {
  if (const toml::table* t = node.as_table()) {
    for (const auto& [k, v] : *t) {
      const std::string key(k.str());
      const bool path_key = key == "file" || (fe && (key == "mass" || key == "stiffness" || key == "dofs" || key == "nodes"));
      if (path_key && v.is_string()) out->push_back(&v);
      else CollectPaths(v, fe && key == "part", out);  // [[fe.part]] tables name files as [fe] does
    }
  } else if (const toml::array* a = node.as_array()) {
    for (const toml::node& e : *a) CollectPaths(e, fe, out);
  }
}

// A name for `target` inside the bundle folder that no other bundled file has taken: the file's
// own name, else name-2, name-3, ... before the extension.
std::string BundleName(const fs::path& target, std::map<std::string, fs::path>* taken) {
  const std::string stem = target.stem().string(), ext = target.extension().string();
  for (int i = 1;; ++i) {
    const std::string name = i == 1 ? target.filename().string() : stem + "-" + std::to_string(i) + ext;
    auto [it, inserted] = taken->emplace(name, target);
    if (inserted || it->second == target) return name;
  }
}

// Rewrites every path-valued string of the model text for the output `out`. A path whose file
// lies inside the output's folder is written relative to it; one that leaves the folder is
// written absolute, so the model loads wherever it is copied on this machine (a `../..` path
// breaks as soon as the file moves). With `bundle`, every referenced file is copied into
// `<out's stem>-files/` beside the output and named relative to it: the folder then travels.
std::string RewritePaths(const std::string& text, const fs::path& in_model, const fs::path& out,
                         const ModelWriteOptions& options) {
  toml::table root;
  try {
    root = toml::parse(text, in_model.string());
  } catch (const toml::parse_error& e) {
    throw InputError(in_model.string() + ":" + std::to_string(e.source().begin.line), std::string(e.description()));
  }
  std::vector<const toml::node*> nodes;
  for (const auto& [k, v] : root) CollectPaths(v, std::string(k.str()) == "fe", &nodes);
  const fs::path in_dir = fs::absolute(in_model).parent_path();
  const fs::path out_dir = fs::weakly_canonical(fs::absolute(out).parent_path());
  const std::string bundle_folder = out.stem().string() + "-files";
  std::map<std::string, fs::path> bundled;  // name in the bundle folder -> the file copied there
  if (options.bundle) {
    // Files already in the bundle folder keep their names, so no copy can replace one of them.
    const fs::path folder = out_dir / bundle_folder;
    for (const toml::node* n : nodes) {
      const fs::path p(*n->value<std::string>());
      if (p.empty()) continue;
      const fs::path target = fs::weakly_canonical(p.is_absolute() ? p : in_dir / p);
      if (target.parent_path() == fs::weakly_canonical(folder)) bundled.emplace(target.filename().string(), target);
    }
  }
  struct Edit {
    size_t first, last;
    std::string replacement;
  };
  std::vector<Edit> edits;
  for (const toml::node* n : nodes) {
    const fs::path p(*n->value<std::string>());
    if (p.empty()) continue;
    const fs::path target = fs::weakly_canonical(p.is_absolute() ? p : in_dir / p);
    std::string now;
    if (options.bundle) {
      const std::string name = BundleName(target, &bundled);
      const fs::path copy = out_dir / bundle_folder / name;
      if (fs::weakly_canonical(copy) != target) {  // re-bundling a bundled model copies nothing
        std::ifstream in(target, std::ios::binary);
        if (!in) throw InputError(in_model.string() + ":" + std::to_string(n->source().begin.line),
                                  "cannot bundle '" + p.string() + "': file " + target.string() + " not found");
        std::ostringstream bytes;
        bytes << in.rdbuf();
        fs::create_directories(copy.parent_path());
        WriteTextFileAtomically(copy, bytes.str());
      }
      now = (fs::path(bundle_folder) / name).generic_string();
    } else {
      const fs::path rel = target.lexically_relative(out_dir);
      const bool inside = !rel.empty() && *rel.begin() != "..";
      now = inside ? rel.generic_string() : target.generic_string();
    }
    if (now == p.generic_string()) continue;
    const auto [first, last] = LiteralAt(text, n->source().begin.line, n->source().begin.column);
    if (first == std::string::npos) continue;
    std::string quoted = "\"";
    for (char c : now) quoted += (c == '"' || c == '\\') ? std::string("\\") + c : std::string(1, c);
    edits.push_back({first, last, quoted + "\""});
  }
  std::sort(edits.begin(), edits.end(), [](const Edit& a, const Edit& b) { return a.first > b.first; });
  std::string s = text;
  for (const Edit& e : edits) s.replace(e.first, e.last - e.first, e.replacement);
  return s;
}

}  // namespace

void WriteModelWithEffects(const std::filesystem::path& in_model, const std::filesystem::path& out,
                           const std::vector<model::Effect>& effects, const ModelWriteOptions& options) {
  std::ifstream in(in_model, std::ios::binary);
  if (!in) throw InputError(in_model.string(), "cannot open model file");
  std::ostringstream text;
  text << in.rdbuf();
  // Curve, [fe] and node-list paths are rewritten to stay valid wherever the output is copied.
  std::string s = RewritePaths(text.str(), in_model, out, options);
  if (!s.empty() && s.back() != '\n') s += '\n';
  for (const model::Effect& e : effects) {
    s += '\n';
    s += EffectToToml(e);
  }
  WriteTextFileAtomically(out, s);
}

}  // namespace ema::formats
