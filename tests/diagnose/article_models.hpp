// The articles of the diagnosis tests and benchmarks as model files (no test framework here, so
// that bench/diagnose.cpp can build the same models): the two-body stack on bolted joints and
// mounts, the FE bar on two supports, the two-body air-film guideway.
#pragma once

#include <Eigen/Dense>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace ema::test_chain {

namespace fs = std::filesystem;

inline void Write(const fs::path& p, const std::string& text) {
  fs::create_directories(p.parent_path());
  std::ofstream(p) << text;
}

inline std::string Vec(double x, double y, double z) {
  std::ostringstream s;
  s << "[" << x << ", " << y << ", " << z << "]";
  return s.str();
}

// Air-film load-lift table of one pad: exponential (vertical) or inverse-square (lateral).
inline std::string FilmArrays(bool exponential, bool csv = false) {
  std::ostringstream gap, load;
  for (int i = 0; i <= 80; ++i) {
    const double h = (0.5 + 0.75 * i) * 1e-6;
    const double w = exponential ? 300.0 * std::exp(-h / 6e-6) : 80.0 * std::pow(5e-6 / h, 2.0);
    if (csv) {
      gap << h << "," << w << "\n";
      continue;
    }
    gap << (i ? ", " : "") << h;
    load << (i ? ", " : "") << w;
  }
  if (csv) return "gap,load\n" + gap.str();
  return "gap = [" + gap.str() + "], load = [" + load.str() + "]";
}

/// The two-body guideway of the real-chain tests: carriage on 4 vertical (exponential W(h)) and 4
/// lateral (inverse-square W(h)) air-film pads over a base on 12 mount springs, 8 test points,
/// setups stud-5um / stud-9um. `lateral_file` non-empty: the lateral curve is read from that CSV
/// (written by the caller with FilmArrays(false, true)), relative to the model's folder.
inline std::string ModelToml(const std::string& lateral_group = "bearings", const std::string& lateral_file = "") {
  std::ostringstream m;
  m.precision(10);
  m << "[model]\nname = \"two-body guideway (test)\"\n\n"
    << "[[body]]\nname = \"carriage\"\nmass = 2.88\ninertia = [0.0117763, 0.0151621, 0.0104617]\ncentre = [0.0, 0.0, 0.0]\n\n"
    << "[[body]]\nname = \"base\"\nmass = 12.0\ninertia = [0.08, 0.10, 0.15]\ncentre = [0.0, 0.0, -0.08]\n\n"
    << "[damping]\nratio = 0.01\n\n";
  int n = 0;
  const std::string vertical = FilmArrays(true);
  const std::string lateral = lateral_file.empty() ? FilmArrays(false) : "file = \"" + lateral_file + "\"";
  for (double x : {-0.06, 0.06})
    for (double y : {-0.03, 0.03})
      m << "[[spring]]\nname = \"V" << ++n << "\"\ngroup = \"bearings\"\na = { body = \"carriage\", at = "
        << Vec(x, y, -0.03) << " }\nb = { body = \"base\" }\ndirection = [0, 0, 1]\n"
        << "law = { series = { setting = 5.0e-6, elements = [ { air_film = { " << vertical << " } } ] } }\n\n";
  for (double x : {-0.06, 0.06})
    for (double y : {-0.045, 0.045})
      m << "[[spring]]\nname = \"L" << ++n << "\"\ngroup = \"" << lateral_group
        << "\"\na = { body = \"carriage\", at = " << Vec(x, y, 0.0) << " }\nb = { body = \"base\" }\ndirection = "
        << Vec(0, y > 0 ? -1.0 : 1.0, 0) << "\n"
        << "law = { series = { setting = 5.0e-6, elements = [ { air_film = { " << lateral << " } } ] } }\n\n";
  m << "[[spring]]\nname = \"drive\"\ngroup = \"drive\"\na = { body = \"carriage\", at = [0, 0, 0] }\n"
       "b = { body = \"base\" }\ndirection = [1, 0, 0]\nlaw = { linear = { k = 3.0e6 } }\n\n";
  for (double x : {-0.1, 0.1})
    for (double y : {-0.08, 0.08}) {
      const std::string at = Vec(x, y, -0.1);
      ++n;
      m << "[[spring]]\nname = \"MZ" << n << "\"\ngroup = \"mounts\"\na = { body = \"base\", at = " << at
        << " }\nb = { body = \"ground\" }\ndirection = [0, 0, 1]\nlaw = { linear = { k = 8.0e6 } }\n\n"
        << "[[spring]]\nname = \"MX" << n << "\"\ngroup = \"mounts\"\na = { body = \"base\", at = " << at
        << " }\nb = { body = \"ground\" }\ndirection = [1, 0, 0]\nlaw = { linear = { k = " << (x > 0 ? 3.0e6 : 2.0e6)
        << " } }\n\n"
        << "[[spring]]\nname = \"MY" << n << "\"\ngroup = \"mounts\"\na = { body = \"base\", at = " << at
        << " }\nb = { body = \"ground\" }\ndirection = [0, 1, 0]\nlaw = { linear = { k = 3.0e6 } }\n\n";
    }
  int id = 101;
  for (double x : {-0.06, 0.06})
    for (double y : {-0.03, 0.03})
      m << "[[point]]\nid = " << id++ << "\nbody = \"carriage\"\nat = " << Vec(x, y, 0.03) << "\n\n";
  id = 201;
  for (double x : {-0.1, 0.1})
    for (double y : {-0.08, 0.08})
      m << "[[point]]\nid = " << id++ << "\nbody = \"base\"\nat = " << Vec(x, y, -0.06) << "\n\n";
  m << "[[setup]]\nname = \"stud-5um\"\noperating = { bearings = 5.0e-6 }\n\n"
    << "[[setup]]\nname = \"stud-9um\"\noperating = { bearings = 9.0e-6 }\n";
  return m.str();
}

// ---- the two-body stack ----

inline std::string StackToml() {
  std::ostringstream m;
  m.precision(10);
  m << "[model]\nname = \"two-body stack on bolted joints and mounts\"\n\n"
    << "[[body]]\nname = \"top\"\nmass = 5.0\ninertia = [0.02, 0.03, 0.045]\ncentre = [0.01, 0.005, 0.05]\n"
    << "uncertainty = 0.02  # weighed\n\n"
    << "[[body]]\nname = \"base\"\nmass = 12.0\ninertia = [0.08, 0.10, 0.15]\ncentre = [0.0, 0.0, -0.05]\n"
    << "uncertainty = 0.02\n\n[damping]\nratio = 0.01\n\n";
  int j = 0;
  for (double x : {-0.08, 0.08})
    for (double y : {-0.06, 0.06}) {
      ++j;
      const double k[] = {8e6 + 2e6 * (x > 0), 6e6, 2.5e7};
      const char* axis[] = {"X", "Y", "Z"};
      for (int d = 0; d < 3; ++d)
        m << "[[spring]]\nname = \"J" << j << axis[d] << "\"\ngroup = \"joints\"\na = { body = \"top\", at = "
          << Vec(x, y, 0.0) << " }\nb = { body = \"base\" }\ndirection = "
          << Vec(d == 0 ? 1 : 0, d == 1 ? 1 : 0, d == 2 ? 1 : 0) << "\nlaw = { linear = { k = " << k[d] << " } }\n\n";
    }
  j = 0;
  for (double x : {-0.1, 0.1})
    for (double y : {-0.08, 0.08}) {
      ++j;
      const double k[] = {3e6 - 1e6 * (y > 0), 2.5e6, 8e6};
      const char* axis[] = {"X", "Y", "Z"};
      for (int d = 0; d < 3; ++d)
        m << "[[spring]]\nname = \"M" << j << axis[d] << "\"\ngroup = \"mounts\"\na = { body = \"base\", at = "
          << Vec(x, y, -0.1) << " }\nb = { body = \"ground\" }\ndirection = "
          << Vec(d == 0 ? 1 : 0, d == 1 ? 1 : 0, d == 2 ? 1 : 0) << "\nlaw = { linear = { k = " << k[d] << " } }\n\n";
    }
  int id = 101;
  for (double x : {-0.07, 0.07})
    for (double y : {-0.05, 0.05}) m << "[[point]]\nid = " << id++ << "\nbody = \"top\"\nat = " << Vec(x, y, 0.08) << "\n\n";
  id = 201;
  for (double x : {-0.1, 0.1})
    for (double y : {-0.08, 0.08}) m << "[[point]]\nid = " << id++ << "\nbody = \"base\"\nat = " << Vec(x, y, -0.06) << "\n\n";
  return m.str();
}

// ---- the FE beam: 8 Euler–Bernoulli elements (uz, ry per node) on two support springs ----
// A steel bar 0.8 m x 40 mm x 20 mm: dir/fe/{M,K}.mtx, dofs.csv, nodes.csv and dir/beam.toml
// (relative [fe] paths; springs S1 at node 1 and S2 at node 9; points 101..109 at nodes 1..9).

inline void WriteBeam(const fs::path& dir) {
  const int elements = 8, nodes = elements + 1, n = 2 * nodes;
  const double length = 0.8, ei = 2.1e11 * 0.04 * std::pow(0.02, 3) / 12.0, mass_per_m = 7850.0 * 0.04 * 0.02;
  const double le = length / elements;
  Eigen::MatrixXd k = Eigen::MatrixXd::Zero(n, n), m = Eigen::MatrixXd::Zero(n, n);
  Eigen::Matrix4d ke, me;
  ke << 12, 6 * le, -12, 6 * le, 6 * le, 4 * le * le, -6 * le, 2 * le * le, -12, -6 * le, 12, -6 * le, 6 * le,
      2 * le * le, -6 * le, 4 * le * le;
  ke *= ei / std::pow(le, 3);
  me << 156, 22 * le, 54, -13 * le, 22 * le, 4 * le * le, 13 * le, -3 * le * le, 54, 13 * le, 156, -22 * le, -13 * le,
      -3 * le * le, -22 * le, 4 * le * le;
  me *= mass_per_m * le / 420.0;
  for (int e = 0; e < elements; ++e) {
    k.block(2 * e, 2 * e, 4, 4) += ke;
    m.block(2 * e, 2 * e, 4, 4) += me;
  }
  auto write = [&](const fs::path& p, const Eigen::MatrixXd& a) {
    std::ostringstream s;
    s.precision(17);
    int count = 0;
    std::ostringstream body;
    body.precision(17);
    for (int c = 0; c < n; ++c)
      for (int r = c; r < n; ++r)
        if (a(r, c) != 0.0) {
          body << r + 1 << " " << c + 1 << " " << a(r, c) << "\n";
          ++count;
        }
    s << "%%MatrixMarket matrix coordinate real symmetric\n" << n << " " << n << " " << count << "\n" << body.str();
    Write(p, s.str());
  };
  write(dir / "fe" / "M.mtx", m);
  write(dir / "fe" / "K.mtx", k);
  std::ostringstream dofs, xyz;
  dofs << "node,dof\n";
  xyz << "node,x,y,z\n";
  for (int i = 1; i <= nodes; ++i) {
    dofs << i << ",uz\n" << i << ",ry\n";
    xyz << i << "," << (i - 1) * le << ",0,0\n";
  }
  Write(dir / "fe" / "dofs.csv", dofs.str());
  Write(dir / "fe" / "nodes.csv", xyz.str());
  std::ostringstream model;
  model << "[model]\nname = \"steel bar on two supports (FE)\"\n\n[fe]\nmass = \"fe/M.mtx\"\nstiffness = \"fe/K.mtx\"\n"
        << "dofs = \"fe/dofs.csv\"\nnodes = \"fe/nodes.csv\"\n\n[damping]\nratio = 0.01\n\n";
  for (int s = 0; s < 2; ++s)
    model << "[[spring]]\nname = \"S" << s + 1 << "\"\ngroup = \"supports\"\na = { node = " << (s ? nodes : 1)
          << " }\nb = { body = \"ground\" }\ndirection = [0, 0, 1]\nlaw = { linear = { k = 3.0e5 } }\n\n";
  for (int i = 1; i <= nodes; ++i) model << "[[point]]\nid = " << 100 + i << "\nnode = " << i << "\n\n";
  Write(dir / "beam.toml", model.str());
}

}  // namespace ema::test_chain
