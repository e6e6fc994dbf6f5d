// A footbridge-like FE model built from parts, for the tests and benchmarks of FE parts
// (model-format.md "FE models built from parts"): two steel girders along x on bearings at both
// ends, cross beams between them, 3D Euler–Bernoulli beam elements (6 DOFs per node), a lumped
// mass matrix whose rotations carry no mass (a singular M, as lumped-mass exports are). Parts:
//   girders/G1..G<zones>  the girder elements of each zone along the span (a group of members),
//   cross/X1..X<zones/2>  the cross beams, two zones each,
//   bearings/B1..B4       one support spring per bearing (three translations to ground: a part
//                         whose matrix is singular on its own),
//   deck                  a part in no group: a thin deck plate's bending stiffness between the
//                         girders (extra stiffness on the cross-beam DOFs),
// [fe] stiffness = nothing (every element belongs to a part), [fe] mass = the lumped mass.
// Test points: `points_per_girder` nodes on each girder, measured in +Z.
#pragma once

#include <Eigen/Dense>
#include <Eigen/SparseCore>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "ema/formats/matrix_market.hpp"

namespace ema::testing {

struct FrameSpec {
  int segments = 80;           ///< elements per girder (DOFs = 12 (segments + 1))
  int zones = 8;               ///< girder zones (parts G1..), cross-beam parts X1.. = zones / 2
  int cross_every = 4;         ///< a cross beam every that many girder nodes
  int points_per_girder = 29;  ///< test points per girder (+Z measured)
  double length = 20.0, width = 2.0;  ///< m
  double bearing_k = 5e8;      ///< N/m per translation per bearing
  double part_uncertainty = 0.3;
  /// Stated uncertainty of the bearing parts B1.. and of the deck part; NaN: part_uncertainty.
  double bearing_uncertainty = std::numeric_limits<double>::quiet_NaN();
  double deck_uncertainty = std::numeric_limits<double>::quiet_NaN();
};

struct FrameFiles {
  std::filesystem::path model;  ///< model.toml
  int dofs = 0;
  int parts = 0;
};

namespace frame_detail {

// 12 x 12 stiffness of a 3D Euler–Bernoulli beam element along its local x (u, v, w, θx, θy, θz
// at each end).
inline Eigen::Matrix<double, 12, 12> LocalStiffness(double e, double g, double a, double iy, double iz, double j, double l) {
  Eigen::Matrix<double, 12, 12> k = Eigen::Matrix<double, 12, 12>::Zero();
  const double ea = e * a / l, gj = g * j / l;
  k(0, 0) = k(6, 6) = ea;
  k(0, 6) = k(6, 0) = -ea;
  k(3, 3) = k(9, 9) = gj;
  k(3, 9) = k(9, 3) = -gj;
  auto bend = [&](int v, int t, double ei, double sign) {  // v: transverse, t: rotation about the other axis
    const double c1 = 12 * ei / (l * l * l), c2 = 6 * ei / (l * l), c3 = 4 * ei / l, c4 = 2 * ei / l;
    const int v1 = v, t1 = t, v2 = v + 6, t2 = t + 6;
    k(v1, v1) += c1, k(v2, v2) += c1, k(v1, v2) -= c1, k(v2, v1) -= c1;
    k(v1, t1) += sign * c2, k(t1, v1) += sign * c2, k(v1, t2) += sign * c2, k(t2, v1) += sign * c2;
    k(v2, t1) -= sign * c2, k(t1, v2) -= sign * c2, k(v2, t2) -= sign * c2, k(t2, v2) -= sign * c2;
    k(t1, t1) += c3, k(t2, t2) += c3, k(t1, t2) += c4, k(t2, t1) += c4;
  };
  bend(1, 5, e * iz, 1.0);   // v with θz
  bend(2, 4, e * iy, -1.0);  // w with θy
  return k;
}

// Rotation of the element's local axes to global: local x along `axis`, local z up where possible.
inline Eigen::Matrix<double, 12, 12> Transform(const Eigen::Vector3d& axis) {
  const Eigen::Vector3d x = axis.normalized();
  Eigen::Vector3d up = std::abs(x.z()) > 0.9 ? Eigen::Vector3d::UnitY() : Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d y = up.cross(x).normalized();
  const Eigen::Vector3d z = x.cross(y);
  Eigen::Matrix3d r;
  r.row(0) = x;
  r.row(1) = y;
  r.row(2) = z;
  Eigen::Matrix<double, 12, 12> t = Eigen::Matrix<double, 12, 12>::Zero();
  for (int b = 0; b < 4; ++b) t.block<3, 3>(3 * b, 3 * b) = r;
  return t;
}

}  // namespace frame_detail

/// Writes the frame (matrices, DOF map, node list, model.toml with `extra` appended) into `dir`.
inline FrameFiles WriteFrame(const std::filesystem::path& dir, const FrameSpec& spec = {}, const std::string& extra = "") {
  namespace fs = std::filesystem;
  fs::create_directories(dir);
  const int per_girder = spec.segments + 1, nodes = 2 * per_girder, n = 6 * nodes;
  const double dx = spec.length / spec.segments;
  const int id_base = spec.segments < 999 ? 1000 : 1000000;  // girder g's node i: id_base (g + 1) + i
  auto node_id = [&](int girder, int i) { return id_base * (girder + 1) + i; };
  auto position = [&](int girder, int i) { return Eigen::Vector3d(dx * i, girder == 0 ? 0.0 : spec.width, 0.0); };
  auto dof = [&](int girder, int i, int d) { return 6 * (girder * per_girder + i) + d; };
  // Steel sections: girder I-beam, cross beam, deck plate strip.
  const double e = 210e9, g = 81e9, rho = 7850.0;
  struct Section {
    double a, iy, iz, j;
  };
  const Section girder{0.012, 4.0e-4, 6.0e-5, 2.0e-6}, cross{0.004, 2.0e-5, 1.0e-5, 5.0e-7}, deck{0.002, 3.0e-6, 2.0e-5, 1.0e-6};
  std::map<std::string, std::vector<Eigen::Triplet<double>>> parts;  // name -> stiffness entries
  std::vector<std::string> order;
  auto part = [&](const std::string& name) -> std::vector<Eigen::Triplet<double>>& {
    if (!parts.count(name)) order.push_back(name);
    return parts[name];
  };
  Eigen::VectorXd mass = Eigen::VectorXd::Zero(n);
  auto element = [&](const std::string& name, int ga, int ia, int gb, int ib, const Section& s, double density) {
    const Eigen::Vector3d axis = position(gb, ib) - position(ga, ia);
    const double l = axis.norm();
    const Eigen::Matrix<double, 12, 12> t = frame_detail::Transform(axis);
    const Eigen::Matrix<double, 12, 12> k = t.transpose() * frame_detail::LocalStiffness(e, g, s.a, s.iy, s.iz, s.j, l) * t;
    int map[12];
    for (int d = 0; d < 6; ++d) map[d] = dof(ga, ia, d), map[6 + d] = dof(gb, ib, d);
    auto& entries = part(name);
    for (int r = 0; r < 12; ++r)
      for (int c = 0; c < 12; ++c)
        if (k(r, c) != 0.0) entries.emplace_back(map[r], map[c], k(r, c));
    const double m = density * s.a * l / 2.0;  // lumped: half to each end, translations only
    for (int d = 0; d < 3; ++d) mass(map[d]) += m, mass(map[6 + d]) += m;
  };
  for (int gi = 0; gi < 2; ++gi)
    for (int i = 0; i < spec.segments; ++i) {
      const int zone = std::min(spec.zones - 1, i * spec.zones / spec.segments);
      element("G" + std::to_string(zone + 1), gi, i, gi, i + 1, girder, rho);
    }
  for (int i = 0; i <= spec.segments; i += spec.cross_every) {
    const int zone = std::min(spec.zones / 2 - 1, i * (spec.zones / 2) / (spec.segments + 1));
    element("X" + std::to_string(zone + 1), 0, i, 1, i, cross, rho);
    element("deck", 0, i, 1, i, deck, 0.0);
  }
  const int ends[4][2] = {{0, 0}, {1, 0}, {0, spec.segments}, {1, spec.segments}};
  for (int b = 0; b < 4; ++b)
    for (int d = 0; d < 3; ++d) part("B" + std::to_string(b + 1)).emplace_back(dof(ends[b][0], ends[b][1], d), dof(ends[b][0], ends[b][1], d), spec.bearing_k);
  FrameFiles files;
  files.dofs = n;
  std::ostringstream toml;
  toml << "[model]\nname = \"two-girder footbridge (test article)\"\n\n[fe]\nmass = \"M.mtx\"\ndofs = \"dofs.csv\"\n"
          "nodes = \"nodes.csv\"\n\n";
  for (const std::string& name : order) {
    Eigen::SparseMatrix<double> k(n, n);
    k.setFromTriplets(parts[name].begin(), parts[name].end());
    formats::WriteMatrixMarket(dir / ("K_" + name + ".mtx"), k);
    const std::string group = name[0] == 'G' ? "girders" : name[0] == 'X' ? "cross" : name[0] == 'B' ? "bearings" : "";
    toml << "[[fe.part]]\nname = \"" << name << "\"\n";
    if (!group.empty()) toml << "group = \"" << group << "\"\n";
    const double stated = name[0] == 'B' && !std::isnan(spec.bearing_uncertainty) ? spec.bearing_uncertainty
                          : name == "deck" && !std::isnan(spec.deck_uncertainty) ? spec.deck_uncertainty
                                                                                 : spec.part_uncertainty;
    toml << "stiffness = \"K_" << name << ".mtx\"\nuncertainty = " << stated << "\n\n";
    ++files.parts;
  }
  Eigen::SparseMatrix<double> m(n, n);
  std::vector<Eigen::Triplet<double>> mt;
  for (int i = 0; i < n; ++i)
    if (mass(i) != 0.0) mt.emplace_back(i, i, mass(i));
  m.setFromTriplets(mt.begin(), mt.end());
  formats::WriteMatrixMarket(dir / "M.mtx", m);
  std::ofstream dofs(dir / "dofs.csv"), xyz(dir / "nodes.csv");
  dofs << "node,dof\n";
  xyz << "node,x,y,z\n";
  for (int gi = 0; gi < 2; ++gi)
    for (int i = 0; i < per_girder; ++i) {
      for (int d = 0; d < 6; ++d) dofs << node_id(gi, i) << "," << d + 1 << "\n";
      const Eigen::Vector3d p = position(gi, i);
      xyz << node_id(gi, i) << "," << p.x() << "," << p.y() << "," << p.z() << "\n";
    }
  toml << "[damping]\nratio = 0.01\n\n";
  for (int gi = 0; gi < 2; ++gi)
    for (int k = 0; k < spec.points_per_girder; ++k) {
      const int i = 1 + k * (spec.segments - 2) / std::max(1, spec.points_per_girder - 1);
      toml << "[[point]]\nid = " << node_id(gi, i) << "\nnode = " << node_id(gi, i) << "\n\n";
    }
  toml << extra;
  files.model = dir / "model.toml";
  std::ofstream(files.model) << toml.str();
  return files;
}

}  // namespace ema::testing
