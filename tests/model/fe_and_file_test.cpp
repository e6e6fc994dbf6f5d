// FE matrices through Matrix Market files and the sparse path; the model file reader/writer.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

#include "ema/core/error.hpp"
#include "ema/formats/matrix_market.hpp"
#include "ema/formats/model_file.hpp"
#include "ema/formats/uff.hpp"
#include "ema/model/solve.hpp"
#include "test_util.hpp"

using ema::model::EffectTarget;

namespace ema::model {
namespace {

namespace fs = std::filesystem;

/// Clamped Euler-Bernoulli cantilever of `elements` cubic Hermite elements (uz, ry per node), or
/// with `free` the same beam free-free (node 0 kept), written as M.mtx, K.mtx, dofs.csv, nodes.csv
/// and a model file; returns the model path.
fs::path WriteCantilever(const fs::path& dir, int elements, double length, double ei, double rho_a, bool free = false) {
  const int nodes = elements + 1, first = free ? 0 : 1, n = 2 * (nodes - first);  // clamped: node 0's DOFs removed
  const double l = length / elements;
  Eigen::Matrix4d ke, me;
  ke << 12, 6 * l, -12, 6 * l, 6 * l, 4 * l * l, -6 * l, 2 * l * l, -12, -6 * l, 12, -6 * l, 6 * l, 2 * l * l, -6 * l,
      4 * l * l;
  ke *= ei / (l * l * l);
  me << 156, 22 * l, 54, -13 * l, 22 * l, 4 * l * l, 13 * l, -3 * l * l, 54, 13 * l, 156, -22 * l, -13 * l, -3 * l * l,
      -22 * l, 4 * l * l;
  me *= rho_a * l / 420.0;
  std::vector<Eigen::Triplet<double>> kt, mt;
  for (int e = 0; e < elements; ++e)
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j) {
        const int gi = 2 * (e - first) + i, gj = 2 * (e - first) + j;  // global index (< 0: the clamped node)
        if (gi < 0 || gj < 0) continue;
        kt.emplace_back(gi, gj, ke(i, j));
        mt.emplace_back(gi, gj, me(i, j));
      }
  Eigen::SparseMatrix<double> k(n, n), m(n, n);
  k.setFromTriplets(kt.begin(), kt.end());
  m.setFromTriplets(mt.begin(), mt.end());
  formats::WriteMatrixMarket(dir / "K.mtx", k);
  formats::WriteMatrixMarket(dir / "M.mtx", m);
  std::ofstream dofs(dir / "dofs.csv"), xyz(dir / "nodes.csv");
  dofs << "node,dof\n";
  xyz << "node,x,y,z\n";
  for (int i = first; i < nodes; ++i) dofs << i << ",3\n" << i << ",5\n";
  for (int i = 0; i < nodes; ++i) xyz << i << "," << l * i << ",0,0\n";
  dofs.close();
  xyz.close();
  return testing::WriteText(dir / "beam.toml",
                            "[model]\nname = \"cantilever\"\n[fe]\nmass = \"M.mtx\"\nstiffness = \"K.mtx\"\n"
                            "dofs = \"dofs.csv\"\nnodes = \"nodes.csv\"\n[[point]]\nid = 7\nnode = " +
                                std::to_string(elements) + "\n");
}

// `nodes =` may name a UFF file (dataset 15) instead of a CSV: the same cantilever with its node
// list written as UFF 15 gives the same node positions (exact: the values are short decimals).
TEST(FiniteElement, NodesFromUffDataset15MatchTheCsv) {
  const fs::path dir = testing::TempDir("cantilever-uff-nodes");
  const fs::path csv_model = WriteCantilever(dir, 4, 1.0, 1.0, 1.0);
  const Model from_csv = formats::ReadModelFile(csv_model);
  formats::uff::Nodes15 nodes;
  for (const auto& [id, xyz] : from_csv.fe.node_positions)
    nodes.nodes.push_back({id, 0, 0, 8, {xyz[0], xyz[1], xyz[2]}});
  formats::uff::WriteFile(dir / "nodes.unv", {formats::uff::Dataset{15, 0, 0, {}, nodes}});
  std::ifstream in(csv_model);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  text.replace(text.find("nodes.csv"), 9, "nodes.unv");
  const Model from_uff = formats::ReadModelFile(testing::WriteText(dir / "beam-uff.toml", text));
  ASSERT_EQ(from_uff.fe.node_positions.size(), from_csv.fe.node_positions.size());
  for (const auto& [id, xyz] : from_csv.fe.node_positions)
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(from_uff.fe.node_positions.at(id)[k], xyz[k], 1e-9) << "node " << id;
}

TEST(FiniteElement, CantileverMatchesEulerBernoulliThroughSparsePath) {
  const double length = 1.0, e = 210e9, b = 0.02, h = 0.01, rho = 7850.0;
  const double ei = e * b * h * h * h / 12.0, rho_a = rho * b * h;
  const fs::path path = WriteCantilever(testing::TempDir("cantilever"), 60, length, ei, rho_a);
  const Model model = formats::ReadModelFile(path);
  SolveOptions options;
  options.max_modes = 4;
  options.sparse_threshold = 10;  // force the shift-invert path on this 120-DOF model
  const Solution sol = Solve(model, options);
  EXPECT_TRUE(sol.sparse);
  ASSERT_EQ(sol.modes.modes.size(), 4u);
  EXPECT_TRUE(sol.rigid_body_frequencies_hz.empty());
  const double beta_l[] = {1.87510407, 4.69409113, 7.85475744, 10.99554073};
  for (int i = 0; i < 4; ++i) {
    const double f = beta_l[i] * beta_l[i] / (length * length) * std::sqrt(ei / rho_a) / kTwoPi;
    // 60 cubic Hermite elements converge as h^4 (Euler-Bernoulli closed form): the fourth mode
    // is 8e-7 high, the first 4e-10. 5e-6 bounds that with margin; a wrong element matrix
    // (a mass term off by a few percent, a lumped mass) is orders of magnitude further off.
    EXPECT_NEAR(sol.modes.modes[i].frequency_hz, f, 5e-6 * f) << "mode " << i + 1;
  }
  // Tip test point: +Z shape non-zero, +X/+Y zero (no such FE DOF); geometry from nodes.csv.
  EXPECT_GT(std::abs(sol.modes.modes[0].shape[2].real()), 0.0);
  EXPECT_EQ(sol.modes.modes[0].shape[0], std::complex<double>(0.0, 0.0));
  ASSERT_EQ(sol.modes.geometry.size(), 1u);
  EXPECT_NEAR(sol.modes.geometry[0].position.x(), 1.0, 1e-12);
  // The dense path gives the same frequencies (1e-8 relative: both solve to round-off).
  options.sparse_threshold = 100000;
  const Solution dense = Solve(model, options);
  EXPECT_FALSE(dense.sparse);
  for (int i = 0; i < 4; ++i)
    EXPECT_NEAR(dense.modes.modes[i].frequency_hz, sol.modes.modes[i].frequency_hz, 1e-8 * dense.modes.modes[i].frequency_hz);
}

// A finely meshed slender beam: its lowest eigenvalues are 1e-13 of trace(K)/trace(M) (the mean
// eigenvalue grows as the element length to the -4), far above the round-off of a zero eigenvalue
// (~1e-16 of it), and must stay elastic modes. With the rigid-body limit at 1e-12 of that mean the
// sparse path called the cantilever's first mode rigid (1 000 elements: λ₁ = 3.8e-13 of the mean),
// and a 50 004-DOF frame lost its four lowest modes (0.86–4.6 Hz) to it. The free-free beam's two
// rigid-body modes (translation and rotation in the plane) must still be found as such.
TEST(FiniteElement, FineSlenderBeamKeepsItsLowestModesAndFindsItsRigidBodyModes) {
  const double length = 1.0, e = 210e9, b = 0.02, h = 0.01, rho = 7850.0;
  const double ei = e * b * h * h * h / 12.0, rho_a = rho * b * h, omega = std::sqrt(ei / rho_a) / (length * length);
  SolveOptions options;
  options.max_modes = 3;
  for (const bool free : {false, true}) {
    SCOPED_TRACE(free ? "free-free" : "cantilever");
    const fs::path path =
        WriteCantilever(testing::TempDir(free ? "fine-free-beam" : "fine-cantilever"), 1000, length, ei, rho_a, free);
    const Model model = formats::ReadModelFile(path);
    const Solution sol = Solve(model, options);
    // Every computed eigenvalue carries a round-off of ~1e-16 of trace(K)/trace(M) (7e-17 here):
    // the cantilever's first frequency is 1e-4 off for it, not for the mesh (1 000 Hermite
    // elements converge far below 1e-8). 1e-15 of the scale bounds it with margin.
    const double round_off = 1e-15 * model.fe.stiffness.diagonal().sum() / model.fe.mass.diagonal().sum();
    EXPECT_TRUE(sol.sparse);
    EXPECT_EQ(sol.rigid_body_frequencies_hz.size(), free ? 2u : 0u);
    for (double f : sol.rigid_body_frequencies_hz) EXPECT_LT(std::pow(kTwoPi * f, 2), round_off) << "round-off, not a mode";
    // Euler–Bernoulli βL of the clamped-free and free-free beam.
    const double clamped[] = {1.87510407, 4.69409113, 7.85475744}, freefree[] = {4.73004074, 7.85320462, 10.99560784};
    ASSERT_EQ(sol.modes.modes.size(), 3u);
    for (int i = 0; i < 3; ++i) {
      const double bl = free ? freefree[i] : clamped[i];
      const double lambda = std::pow(bl * bl * omega, 2);
      EXPECT_NEAR(std::pow(kTwoPi * sol.modes.modes[i].frequency_hz, 2), lambda, round_off + 1e-8 * lambda) << "mode " << i + 1;
    }
  }
}

// The sparse solver's shift sits just below zero (SolveOptions::sparse_shift, 1e-12 of
// trace(K)/trace(M)), not far below the lowest modes: at 1e-8 of that scale a fine mesh's lowest
// eigenvalues all sat within a few percent of each other after the shift-inversion and Lanczos
// restarted again and again (the 50 004-DOF frame: 8 passes, 297 solves, 11.6 s; 74 and 2.1 s
// now; this 8 000-element cantilever: 205 solves against 74). Same modes either way, to the
// round-off of the mesh's eigenvalues.
TEST(FiniteElement, FineMeshLowestModesConvergeInOneLanczosPass) {
  const double length = 1.0, e = 210e9, b = 0.02, h = 0.01, rho = 7850.0;
  const double ei = e * b * h * h * h / 12.0, rho_a = rho * b * h;
  const fs::path path = WriteCantilever(testing::TempDir("shift-cantilever"), 8000, length, ei, rho_a);
  const Model model = formats::ReadModelFile(path);
  SolveOptions options;
  options.max_modes = 30;
  const Solution near = Solve(model, options);
  options.sparse_shift = 1e-8;
  const Solution far = Solve(model, options);
  ASSERT_TRUE(near.sparse);
  ASSERT_EQ(near.modes.modes.size(), 30u);
  ASSERT_EQ(far.modes.modes.size(), 30u);
  // nev = 36 (30 + room for 6 rigid-body modes) by block Lanczos in blocks of 12 (16 002 DOFs):
  // 11 block solves, 132 columns, the 30 kept pairs converged (Spectra's single-vector Lanczos,
  // until 2026-11-29: 74 solves; the room's pairs converged too: 144 columns). The far shift: 228
  // columns — over twice as many with the basis of three times the pairs, which restarted more;
  // the basis of five times (since 2026-11-29, docs/model.md) absorbs part of that.
  EXPECT_LE(near.shift_invert_solves, 144);
  EXPECT_GT(far.shift_invert_solves, 3 * near.shift_invert_solves / 2) << "the far shift should need more solves";
  // The mesh's own round-off (1e-16 of the scale) bounds how far the two may differ.
  const double round_off = 1e-15 * model.fe.stiffness.diagonal().sum() / model.fe.mass.diagonal().sum();
  for (int i = 0; i < 30; ++i) {
    const double a = std::pow(kTwoPi * near.modes.modes[i].frequency_hz, 2);
    const double z = std::pow(kTwoPi * far.modes.modes[i].frequency_hz, 2);
    EXPECT_NEAR(a, z, round_off + 1e-9 * z) << "mode " << i + 1;
  }
}

TEST(FiniteElement, DofMapNotMatchingMatrixFromFile) {
  const fs::path dir = testing::TempDir("fe_bad");
  const fs::path path = WriteCantilever(dir, 4, 1.0, 1.0, 1.0);
  std::ofstream(dir / "dofs.csv") << "1,3\n1,5\n2,3\n";
  try {
    formats::ReadModelFile(path);
    FAIL();
  } catch (const InputError& e) {
    const std::string s = e.what();
    EXPECT_NE(s.find("dofs.csv"), std::string::npos) << s;
    EXPECT_NE(s.find("3 rows"), std::string::npos) << s;
    EXPECT_NE(s.find("8 rows"), std::string::npos) << s;
  }
}

TEST(MatrixMarket, TruncatedFileIsInputError) {
  const fs::path p = testing::WriteText(testing::TempDir("mm") / "t.mtx",
                                        "%%MatrixMarket matrix coordinate real symmetric\n3 3 3\n1 1 1.0\n2 2 1.0\n");
  try {
    formats::ReadMatrixMarket(p);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("truncated"), std::string::npos) << e.what();
  }
}

TEST(MatrixMarket, AFolderIsInputErrorNotACrash) {
  // Found by the model-file fuzzer: an [fe] path naming a folder made the stream throw
  // std::ios_base::failure, which escaped as a crash instead of exit 1.
  const fs::path dir = testing::TempDir("mm") / "a-folder.mtx";
  fs::create_directories(dir);
  try {
    formats::ReadMatrixMarket(dir);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("is a folder"), std::string::npos) << e.what();
  }
  // The same for any text reader going through ReadTextLine: a curve file that is a folder.
  const fs::path model = testing::WriteText(testing::TempDir("mm") / "curve-folder.toml",
                                            "[model]\nname = \"m\"\n[[body]]\nname = \"b\"\nmass = 1.0\n"
                                            "inertia = [1.0, 1.0, 1.0]\n[[spring]]\nname = \"s\"\ngroup = \"g\"\n"
                                            "a = { body = \"b\", at = [0.0, 0.0, 0.0] }\nb = { body = \"ground\" }\n"
                                            "direction = [0.0, 0.0, 1.0]\nlaw = { table = { file = \"a-folder.mtx\" } }\n");
  EXPECT_THROW(formats::ReadModelFile(model), InputError);
}

const char* kCarriage = R"([model]
name = "pad"

[[body]]
name = "carriage"
mass = 2.88
inertia = [0.0117763, 0.0151621, 0.0104617]

[[spring]]
name = "B1"
group = "bearings"
a = { body = "carriage", at = [0.0624, 0.0, 0.0] }
direction = [0.0, 0.0, 1.0]
law = { series = { setting = 5.0e-6, elements = [ { air_film = { file = "film.csv" } }, { hertz = { modulus = 5e9, radius = 3e-3 } } ] } }

[[spring]]
name = "B2"
group = "bearings"
a = { body = "carriage", at = [-0.0624, 0.0, 0.0] }
b = { body = "ground" }
direction = "+Z"
law = { linear = { k = 2.0e6 } }

[[point]]
id = 101
body = "carriage"
at = [0.06, 0.03, 0.03]

[[setup]]
name = "stud-9um"
operating = { bearings = 9.0e-6 }
)";

fs::path WriteCarriage(const fs::path& dir, const std::string& text = kCarriage) {
  std::ofstream film(dir / "film.csv");
  film << "gap,load\n";
  for (int i = 0; i <= 40; ++i) {
    const double h = 1e-6 + 0.5e-6 * i;
    film << h << "," << 400.0 * std::exp(-h / 4e-6) << "\n";
  }
  film.close();
  return testing::WriteText(dir / "carriage.toml", text);
}

TEST(ModelFile, ReadsLawsAnchorsSetupsAndRelativeCurveFiles) {
  const Model m = formats::ReadModelFile(WriteCarriage(testing::TempDir("file_ok")));
  ASSERT_EQ(m.springs.size(), 2u);
  EXPECT_EQ(m.springs[0].group, "bearings");
  EXPECT_EQ(m.springs[0].line, 9);
  EXPECT_EQ(m.springs[0].law.KindName(), "series");
  EXPECT_EQ(m.springs[1].b.body, "ground");
  EXPECT_EQ(m.springs[1].direction, Eigen::Vector3d::UnitZ());
  ASSERT_EQ(m.setups.size(), 1u);
  EXPECT_DOUBLE_EQ(m.setups[0].operating.at("bearings"), 9e-6);
  // The chain solves: the gap opens beyond the 5 um setting; the 9 um setup is softer.
  const System nominal = Assemble(m);
  SolveOptions o;
  o.setup = "stud-9um";
  const System wide = Assemble(m, o);
  EXPECT_GT(nominal.springs[0].gap, 5e-6);
  EXPECT_GT(wide.springs[0].gap, 9e-6);
  EXPECT_LT(wide.springs[0].stiffness, nominal.springs[0].stiffness);
  EXPECT_DOUBLE_EQ(wide.springs[1].stiffness, 2e6) << "linear laws ignore setups";
}

TEST(ModelFile, UnknownKeyNamesLineAndAllowedKeys) {
  std::string text = kCarriage;
  text.replace(text.find("mass = 2.88"), 11, "masss = 2.88");
  try {
    formats::ReadModelFile(WriteCarriage(testing::TempDir("file_key"), text));
    FAIL();
  } catch (const InputError& e) {
    const std::string s = e.what();
    EXPECT_NE(s.find("carriage.toml:6"), std::string::npos) << s;
    EXPECT_NE(s.find("unknown key 'masss'"), std::string::npos) << s;
    EXPECT_NE(s.find("allowed: centre, inertia, mass"), std::string::npos) << s;
  }
}

TEST(ModelFile, SpringToUnknownBodyNamesSpringAndLine) {
  std::string text = kCarriage;
  const std::string from = "b = { body = \"ground\" }";
  text.replace(text.find(from), from.size(), "b = { body = \"frame\" }");
  try {
    formats::ReadModelFile(WriteCarriage(testing::TempDir("file_body"), text));
    FAIL();
  } catch (const InputError& e) {
    const std::string s = e.what();
    EXPECT_NE(s.find("carriage.toml:16"), std::string::npos) << s;
    EXPECT_NE(s.find("spring 'B2'"), std::string::npos) << s;
    EXPECT_NE(s.find("unknown body 'frame'"), std::string::npos) << s;
  }
}

TEST(ModelFile, BadValueTypeNamesKey) {
  std::string text = kCarriage;
  text.replace(text.find("mass = 2.88"), 11, "mass = \"heavy\"");
  try {
    formats::ReadModelFile(WriteCarriage(testing::TempDir("file_type"), text));
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("key 'mass': expected a number"), std::string::npos) << e.what();
  }
}

TEST(ModelFile, WriteWithEffectsKeepsFileAndRoundTrips) {
  const fs::path dir = testing::TempDir("file_effects");
  const fs::path in = WriteCarriage(dir);
  const fs::path out = dir / "updated.toml";
  Effect series{EffectKind::kSeriesCompliance, EffectTarget::Named("bearings"), {}, Law(LinearLaw{6.5e6}), 0};
  Effect scale{EffectKind::kMassScale, EffectTarget::Named("carriage"), {{"factor", 1.0625}}, std::nullopt, 0};
  Effect fitted{EffectKind::kSeriesCompliance, EffectTarget::Named("bearings"), {{"k", 3.25e7}}, std::nullopt, 0};
  formats::WriteModelWithEffects(in, out, {series, scale, fitted});
  std::ifstream a(in), b(out);
  const std::string original((std::istreambuf_iterator<char>(a)), {}), updated((std::istreambuf_iterator<char>(b)), {});
  EXPECT_EQ(updated.substr(0, original.size()), original);
  const Model m = formats::ReadModelFile(out);
  ASSERT_EQ(m.effects.size(), 3u);
  EXPECT_DOUBLE_EQ(std::get<LinearLaw>(m.effects[2].law->value).k, 3.25e7) << "k written as a linear law";
  EXPECT_EQ(m.effects[0].kind, EffectKind::kSeriesCompliance);
  EXPECT_DOUBLE_EQ(std::get<LinearLaw>(m.effects[0].law->value).k, 6.5e6);
  EXPECT_DOUBLE_EQ(m.effects[1].parameters.at("factor"), 1.0625);
  // Solving the updated file applies its effects: lower frequencies than the original.
  const Model original_model = formats::ReadModelFile(in);
  EXPECT_LT(Solve(m).modes.modes[0].frequency_hz, Solve(original_model).modes.modes[0].frequency_hz);
}

TEST(ModelFile, WrittenElsewhereRewritesRelativePathsAndLoads) {
  // The carriage's air-film curve is a relative `file =`: written into another folder, the model
  // must still find it (the path is rewritten), and nothing else changes.
  const fs::path dir = testing::TempDir("file_elsewhere");
  const fs::path in = WriteCarriage(dir);
  const fs::path out = dir / "deeper" / "still" / "updated.toml";
  fs::create_directories(out.parent_path());
  Effect scale{EffectKind::kMassScale, EffectTarget::Named("carriage"), {{"factor", 1.0625}}, std::nullopt, 0};
  formats::WriteModelWithEffects(in, out, {scale});
  std::ifstream b(out);
  const std::string updated((std::istreambuf_iterator<char>(b)), {});
  // The curve lies outside the output's folder: named absolute, so the model loads wherever it goes.
  EXPECT_NE(updated.find("\"" + fs::weakly_canonical(dir / "film.csv").generic_string() + "\""), std::string::npos) << updated;
  const Model m = formats::ReadModelFile(out);
  const Model original = formats::ReadModelFile(in);
  ASSERT_EQ(m.effects.size(), 1u);
  // Same curve, same solution once the effect is taken out.
  Model without = m;
  without.effects.clear();
  EXPECT_DOUBLE_EQ(Solve(without).modes.modes[0].frequency_hz, Solve(original).modes.modes[0].frequency_hz);
  // Written next to the input, the path is left as it was.
  formats::WriteModelWithEffects(in, dir / "same.toml", {});
  std::ifstream c(dir / "same.toml"), a(in);
  const std::string same((std::istreambuf_iterator<char>(c)), {}), input((std::istreambuf_iterator<char>(a)), {});
  EXPECT_EQ(same, input);
}

}  // namespace
}  // namespace ema::model

namespace ema::model {
namespace {

TEST(ModelFile, MicroSlipLawReadsAndWritesBack) {
  const fs::path dir = testing::TempDir("micro_slip_file");
  const std::string text = R"(
[[body]]
name = "b"
mass = 1.0
inertia = [0.01, 0.01, 0.01]

[[spring]]
name = "J"
group = "joints"
a = { body = "b" }
b = { body = "ground" }
direction = [0.0, 0.0, 1.0]
law = { micro_slip = { k = 2.0e6, slip_force = 4.5, elements = 20 } }
)";
  const Model m = formats::ReadModelFile(testing::WriteText(dir / "m.toml", text));
  const auto* law = std::get_if<MicroSlipLaw>(&m.springs.at(0).law.value);
  ASSERT_NE(law, nullptr);
  EXPECT_DOUBLE_EQ(law->k, 2.0e6);
  EXPECT_DOUBLE_EQ(law->slip_force, 4.5);
  EXPECT_EQ(law->elements, 20);
  EXPECT_EQ(formats::LawToToml(m.springs[0].law), "{ micro_slip = { k = 2000000.0, slip_force = 4.5, elements = 20 } }");
  std::string bad = text;
  bad.replace(bad.find("elements = 20"), 13, "elements = 0");
  EXPECT_THROW(formats::ReadModelFile(testing::WriteText(dir / "bad.toml", bad)), InputError);
  bad = text;
  bad.replace(bad.find("slip_force"), 10, "slip_forse");
  EXPECT_THROW(formats::ReadModelFile(testing::WriteText(dir / "bad2.toml", bad)), InputError);
}

}  // namespace
}  // namespace ema::model
