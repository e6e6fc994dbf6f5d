// FE models built from parts (model-format.md, added turn 3): [[fe.part]] read, assembled,
// scaled by effects, checked as bad input; massless DOFs; the reduced (Ritz) model.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>

#include "ema/core/error.hpp"
#include "ema/formats/matrix_market.hpp"
#include "ema/formats/model_file.hpp"
#include "ema/model/effects.hpp"
#include "ema/model/reduced.hpp"
#include "ema/model/solve.hpp"
#include "fe_frame.hpp"
#include "test_util.hpp"

using ema::model::EffectTarget;

namespace ema::model {
namespace {

namespace fs = std::filesystem;

std::vector<double> Frequencies(const Solution& s) {
  std::vector<double> f;
  for (const auto& m : s.modes.modes) f.push_back(m.frequency_hz);
  return f;
}

// The assembled K and M, dense, from a model (FE DOFs only: the frame has no bodies).
Eigen::MatrixXd DenseK(const Model& m) { return Eigen::MatrixXd(Assemble(m).stiffness); }

// Reference eigenvalues of (K, M) with the massless rotations condensed by hand: a dense Schur
// complement, independent of the solver's own condensation.
std::vector<double> ReferenceFrequencies(const Eigen::MatrixXd& k, const Eigen::VectorXd& mass, int count) {
  std::vector<int> keep, drop;
  for (int i = 0; i < mass.size(); ++i) (mass(i) > 0.0 ? keep : drop).push_back(i);
  const Eigen::MatrixXd kred = k(keep, keep) - k(keep, drop) * k(drop, drop).ldlt().solve(k(drop, keep));
  Eigen::VectorXd minv_sqrt(keep.size());
  for (size_t i = 0; i < keep.size(); ++i) minv_sqrt(static_cast<Eigen::Index>(i)) = 1.0 / std::sqrt(mass(keep[i]));
  const Eigen::MatrixXd a = minv_sqrt.asDiagonal() * kred * minv_sqrt.asDiagonal();
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(0.5 * (a + a.transpose()));
  std::vector<double> f;
  for (int i = 0; i < es.eigenvalues().size() && static_cast<int>(f.size()) < count; ++i)
    if (es.eigenvalues()(i) > 1e-6) f.push_back(std::sqrt(es.eigenvalues()(i)) / kTwoPi);
  return f;
}

class FrameParts : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    ema::testing::FrameSpec spec;
    spec.segments = 24;  // 300 DOFs: dense references stay quick
    spec.points_per_girder = 9;
    files_ = new ema::testing::FrameFiles(ema::testing::WriteFrame(testing::TempDir("frame-parts"), spec));
  }
  static void TearDownTestSuite() { delete files_; }
  static ema::testing::FrameFiles* files_;
};
ema::testing::FrameFiles* FrameParts::files_ = nullptr;

// K = [fe].stiffness + Σ parts, M with massless rotations: the solver's modes are those of the
// summed matrices with the rotations condensed by hand (dense, 1e-9).
TEST_F(FrameParts, PartsSumToTheGlobalStiffnessAndMasslessRotationsCondenseExactly) {
  const Model m = formats::ReadModelFile(files_->model);
  ASSERT_EQ(m.fe.parts.size(), 17u);  // G1..G8, X1..X4, deck, B1..B4
  EXPECT_EQ(m.fe.stiffness.rows(), 0);  // every element is in a part
  Eigen::MatrixXd k = Eigen::MatrixXd::Zero(m.fe.Size(), m.fe.Size());
  for (const FePart& p : m.fe.parts) k += Eigen::MatrixXd(*p.stiffness);
  EXPECT_LT((DenseK(m) - k).norm(), 1e-12 * k.norm());
  const Eigen::VectorXd mass = Eigen::MatrixXd(m.fe.mass).diagonal();
  int massless = 0;
  for (int i = 0; i < mass.size(); ++i) massless += mass(i) == 0.0;
  EXPECT_EQ(massless, m.fe.Size() / 2);  // every rotation
  const std::vector<double> reference = ReferenceFrequencies(k, mass, 12);
  SolveOptions so;
  so.max_modes = 12;
  const std::vector<double> solved = Frequencies(Solve(m, so));
  ASSERT_EQ(solved.size(), reference.size());
  for (size_t i = 0; i < solved.size(); ++i) EXPECT_NEAR(solved[i], reference[i], 1e-9 * reference[i]) << "mode " << i + 1;
  // The sparse shift-invert path (massless DOFs given a mass 1e-12 of the largest) agrees.
  so.sparse_threshold = 10;
  const std::vector<double> sparse = Frequencies(Solve(m, so));
  ASSERT_EQ(sparse.size(), reference.size());
  for (size_t i = 0; i < sparse.size(); ++i) EXPECT_NEAR(sparse[i], reference[i], 1e-7 * reference[i]) << "mode " << i + 1;
}

// stiffness_scale on a member, a group and a lone part multiplies exactly those matrices.
TEST_F(FrameParts, StiffnessScaleTargetsAMemberAGroupAndALonePart) {
  const Model m = formats::ReadModelFile(files_->model);
  const Eigen::MatrixXd k0 = DenseK(m);
  auto part_k = [&](const std::string& name) {
    for (const FePart& p : m.fe.parts)
      if (p.name == name) return Eigen::MatrixXd(*p.stiffness);
    ADD_FAILURE() << "no part " << name;
    return Eigen::MatrixXd();
  };
  const Eigen::MatrixXd member = DenseK(
      ApplyEffect(m, {EffectKind::kStiffnessScale, EffectTarget::MemberOf("girders", "G3"), {{"factor", 0.3}}, {}, 0}));
  EXPECT_LT((member - (k0 - 0.7 * part_k("G3"))).norm(), 1e-12 * k0.norm());
  Eigen::MatrixXd cross = Eigen::MatrixXd::Zero(k0.rows(), k0.cols());
  for (const char* x : {"X1", "X2", "X3", "X4"}) cross += part_k(x);
  const Eigen::MatrixXd group =
      DenseK(ApplyEffect(m, {EffectKind::kStiffnessScale, EffectTarget::Named("cross"), {{"factor", 0.6}}, {}, 0}));
  EXPECT_LT((group - (k0 - 0.4 * cross)).norm(), 1e-12 * k0.norm());
  const Eigen::MatrixXd lone =
      DenseK(ApplyEffect(m, {EffectKind::kStiffnessScale, EffectTarget::Named("deck"), {{"factor", 2.0}}, {}, 0}));
  EXPECT_LT((lone - (k0 + part_k("deck"))).norm(), 1e-12 * k0.norm());
  // A target that names nothing lists the targets there are.
  try {
    ApplyEffect(m, {EffectKind::kStiffnessScale, EffectTarget::MemberOf("girders", "G9"), {{"factor", 0.5}}, {}, 0});
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("no part 'G9' in part group 'girders' (members: G1, G2"), std::string::npos)
        << e.what();
  }
  // Girders carry no mass.
  EXPECT_THROW(ApplyEffect(m, {EffectKind::kMassScale, EffectTarget::Named("girders"), {{"factor", 0.5}}, {}, 0}),
               InputError);
}

// The reduced model: the base's modes and each probe's static responses (first and second order)
// reproduce full solves — at the base to the round-off of projecting a stiffness whose axial
// terms are 1e6 of the bending ones (1e-7), to 1e-5 for a 40 % change of a member, and still to
// 0.5 % for a 20-fold softening (what the diagnosis then re-centres and checks in full).
TEST_F(FrameParts, ReducedModelMatchesFullSolves) {
  const Model m = formats::ReadModelFile(files_->model);
  SolveOptions so;
  so.max_modes = 10;
  ReducedModelOptions ro;
  ro.modes = 20;
  ro.enriched_modes = 10;
  const ReducedModelFactory factory(m, so, ro);
  const Effect probe{EffectKind::kStiffnessScale, EffectTarget::MemberOf("girders", "G3"), {{"factor", 0.5}}, {}, 0};
  const auto reduced = factory.Make({{probe}});
  EXPECT_GT(reduced->BasisSize(), 20);
  EXPECT_LE(reduced->BasisSize(), 40);  // 20 modes + 2 x 10 responses
  for (double factor : {1.0, 0.6, 0.05}) {
    const Effect e{EffectKind::kStiffnessScale, EffectTarget::MemberOf("girders", "G3"), {{"factor", factor}}, {}, 0};
    const std::vector<double> full = Frequencies(Solve(ApplyEffect(m, e), so));
    const std::vector<double> approx = Frequencies(reduced->Solve(ApplyEffect(factory.Skeleton(), e), so));
    ASSERT_EQ(full.size(), approx.size());
    const double tolerance = factor == 1.0 ? 1e-7 : factor == 0.6 ? 1e-5 : 5e-3;
    for (size_t i = 0; i < full.size(); ++i) {
      EXPECT_NEAR(approx[i], full[i], tolerance * full[i]) << "factor " << factor << " mode " << i + 1;
      EXPECT_GE(approx[i], full[i] * (1.0 - 1e-7)) << "Rayleigh-Ritz gives upper bounds";
    }
  }
  // Sensor masses (extra masses of the solve) are a change the reduced model carries too.
  SolveOptions with_sensors = so;
  for (const TestPoint& p : m.points) with_sensors.extra_masses.push_back({"sensor", p.where, 0.5, 0});
  const std::vector<double> full = Frequencies(Solve(m, with_sensors));
  const std::vector<double> approx = Frequencies(reduced->Solve(factory.Skeleton(), with_sensors));
  for (size_t i = 0; i < full.size(); ++i) EXPECT_NEAR(approx[i], full[i], 1e-4 * full[i]) << "mode " << i + 1;
}

// A reduced model of several probes is assembled from blocks the factory keeps per probe and per
// pair (issue 39: no n-sized product per model): the probes in either order give the same
// eigenvalues to round-off (the pair's cross Gram matrices kept once, transposed for the other
// order), a set met again reuses its blocks (its second model the same as its first, bit for bit),
// and the eigenvalues are upper bounds of a full solve's of the two changes together.
TEST_F(FrameParts, ReducedModelOfTwoProbesIsTheSameInEitherOrder) {
  const Model m = formats::ReadModelFile(files_->model);
  SolveOptions so;
  so.max_modes = 10;
  ReducedModelOptions ro;
  ro.modes = 20;
  ro.enriched_modes = 10;
  const ReducedModelFactory factory(m, so, ro);
  const Effect girder{EffectKind::kStiffnessScale, EffectTarget::MemberOf("girders", "G3"), {{"factor", 0.5}}, {}, 0};
  const Effect cross{EffectKind::kStiffnessScale, EffectTarget::MemberOf("cross", "X2"), {{"factor", 0.5}}, {}, 0};
  const auto forward = factory.Make({{girder}, {cross}});
  const auto backward = factory.Make({{cross}, {girder}});
  const auto again = factory.Make({{girder}, {cross}});
  EXPECT_EQ(forward->BasisSize(), backward->BasisSize());
  const Effect g{EffectKind::kStiffnessScale, EffectTarget::MemberOf("girders", "G3"), {{"factor", 0.6}}, {}, 0};
  const Effect x{EffectKind::kStiffnessScale, EffectTarget::MemberOf("cross", "X2"), {{"factor", 0.4}}, {}, 0};
  const Model changed = ApplyEffect(ApplyEffect(factory.Skeleton(), g), x);
  const std::vector<double> full = Frequencies(Solve(ApplyEffect(ApplyEffect(m, g), x), so));
  const std::vector<double> f = Frequencies(forward->Solve(changed, so));
  const std::vector<double> b = Frequencies(backward->Solve(changed, so));
  const std::vector<double> a = Frequencies(again->Solve(changed, so));
  ASSERT_EQ(f.size(), full.size());
  ASSERT_EQ(b.size(), full.size());
  for (size_t i = 0; i < full.size(); ++i) {
    // Same span, another order of the same products: round-off of the probes' Gram matrices,
    // condition numbers up to 1e17 (measured 6e-7 at most with OpenBLAS's Haswell kernels, 1.3e-6
    // with its AVX-512 ones; the basis of the concatenated responses orthogonalised at once, before
    // blocks were kept, differed between the orders by 2.5e-7).
    EXPECT_NEAR(b[i], f[i], 5e-6 * f[i]) << "mode " << i + 1;
    EXPECT_EQ(a[i], f[i]) << "mode " << i + 1;
    // Two changes at once, the cross beam's 60 % beyond its probe's 50 %: Rayleigh-Ritz upper
    // bounds, within 0.3 % (modes 2 and 6, where the cross beam twists the girders: measured
    // 3.5314 against 3.5208 Hz, the same as the concatenated basis gave).
    EXPECT_NEAR(f[i], full[i], 5e-3 * full[i]) << "mode " << i + 1;
    EXPECT_GE(f[i], full[i] * (1.0 - 1e-6)) << "Rayleigh-Ritz gives upper bounds";
  }
}

// A reduced solve projects point masses, springs and sensors from their own entries with the base's
// DOF layout (issue 39): the changed model it is given may leave out its [fe] DOF map and node
// positions — the diagnosis copies a skeleton without them for every evaluation — and solves the
// same, bit for bit, as with them, and as the full model does to the reduced model's accuracy.
TEST_F(FrameParts, ReducedModelSolvesAChangedModelWithoutItsDofMap) {
  const Model m = formats::ReadModelFile(files_->model);
  SolveOptions so;
  so.max_modes = 10;
  ReducedModelOptions ro;
  ro.modes = 20;
  ro.enriched_modes = 10;
  const ReducedModelFactory factory(m, so, ro);
  const EffectTarget point = EffectTarget::Points({m.points.at(3).id});
  const Effect mass{EffectKind::kAddedMass, point, {{"mass", 2.0}}, {}, 0};
  const Effect girder{EffectKind::kStiffnessScale, EffectTarget::MemberOf("girders", "G3"), {{"factor", 0.7}}, {}, 0};
  const auto reduced = factory.Make({{mass}, {girder}});
  SolveOptions with_sensors = so;
  for (const TestPoint& p : m.points) with_sensors.extra_masses.push_back({"sensor", p.where, 0.5, 0});
  Model lean = factory.Skeleton();
  lean.fe.dofs.clear();
  lean.fe.node_positions.clear();
  const std::vector<Effect> effects{
      {EffectKind::kAddedMass, point, {{"mass", 1.5}}, {}, 0},
      {EffectKind::kStiffnessScale, EffectTarget::MemberOf("girders", "G3"), {{"factor", 0.8}}, {}, 0}};
  Model with_map = factory.Skeleton();
  for (const Effect& e : effects) lean = ApplyEffect(lean, e), with_map = ApplyEffect(with_map, e);
  const std::vector<double> a = Frequencies(reduced->Solve(lean, with_sensors));
  const std::vector<double> b = Frequencies(reduced->Solve(with_map, with_sensors));
  Model full = m;
  for (const Effect& e : effects) full = ApplyEffect(full, e);
  const std::vector<double> exact = Frequencies(Solve(full, with_sensors));
  ASSERT_EQ(a.size(), b.size());
  ASSERT_EQ(a.size(), exact.size());
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i], b[i]) << "mode " << i + 1;
    EXPECT_NEAR(a[i], exact[i], 1e-4 * exact[i]) << "mode " << i + 1;
  }
}

// A model written with `-o` (here: the writer of `ema diagnose -o`) names its part files so that it
// loads from another folder and solves the same.
TEST_F(FrameParts, WrittenModelLoadsFromAnotherFolder) {
  const fs::path elsewhere = testing::TempDir("frame-parts-elsewhere") / "sub" / "updated.toml";
  fs::create_directories(elsewhere.parent_path());
  formats::WriteModelWithEffects(
      files_->model, elsewhere,
      {{EffectKind::kStiffnessScale, EffectTarget::MemberOf("girders", "G2"), {{"factor", 0.5}}, {}, 0}});
  const Model written = formats::ReadModelFile(elsewhere);
  const Model here =
      ApplyEffect(formats::ReadModelFile(files_->model),
                  {EffectKind::kStiffnessScale, EffectTarget::MemberOf("girders", "G2"), {{"factor", 0.5}}, {}, 0});
  SolveOptions so;
  so.max_modes = 6;
  const std::vector<double> a = Frequencies(Solve(written, so)), b = Frequencies(Solve(here, so));
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) EXPECT_NEAR(a[i], b[i], 1e-12 * b[i]);
}

// The written model, copied into another folder on the same machine, still loads and solves the
// same: paths that leave the output's folder are written absolute (a `../..` path broke here).
TEST_F(FrameParts, WrittenModelCopiedElsewhereLoadsTheSame) {
  const fs::path root = testing::TempDir("frame-parts-copied");
  const fs::path written = root / "out" / "updated.toml";
  fs::create_directories(written.parent_path());
  const Effect loose{EffectKind::kStiffnessScale, EffectTarget::MemberOf("girders", "G2"), {{"factor", 0.5}}, {}, 0};
  formats::WriteModelWithEffects(files_->model, written, {loose});
  const fs::path copied = root / "a" / "b" / "c" / "copy.toml";
  fs::create_directories(copied.parent_path());
  fs::copy_file(written, copied);
  SolveOptions so;
  so.max_modes = 6;
  const std::vector<double> a = Frequencies(Solve(formats::ReadModelFile(copied), so));
  const std::vector<double> b = Frequencies(Solve(ApplyEffect(formats::ReadModelFile(files_->model), loose), so));
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) EXPECT_NEAR(a[i], b[i], 1e-12 * b[i]);
}

// --bundle: the matrices are copied beside the written model, which names them relative to its
// folder; the whole folder moved to another path (the originals deleted) loads and solves the same.
TEST_F(FrameParts, BundledModelTravelsWithItsFolder) {
  const fs::path root = testing::TempDir("frame-parts-bundled");
  const fs::path out = root / "send" / "updated.toml";
  fs::create_directories(out.parent_path());
  const Effect loose{EffectKind::kStiffnessScale, EffectTarget::MemberOf("girders", "G2"), {{"factor", 0.5}}, {}, 0};
  formats::ModelWriteOptions bundle;
  bundle.bundle = true;
  formats::WriteModelWithEffects(files_->model, out, {loose}, bundle);
  ASSERT_TRUE(fs::is_directory(root / "send" / "updated-files"));
  std::ifstream in(out);
  const std::string text((std::istreambuf_iterator<char>(in)), {});
  EXPECT_NE(text.find("\"updated-files/"), std::string::npos) << text;
  EXPECT_EQ(text.find(root.string()), std::string::npos) << "no absolute path into the old folder:\n" << text;
  // Re-bundling the bundled model in place copies nothing over itself.
  formats::WriteModelWithEffects(out, out.parent_path() / "again.toml", {}, bundle);
  const fs::path moved = testing::TempDir("frame-parts-bundled-moved") / "received";
  fs::remove_all(moved);
  fs::rename(root / "send", moved);
  SolveOptions so;
  so.max_modes = 6;
  const std::vector<double> a = Frequencies(Solve(formats::ReadModelFile(moved / "updated.toml"), so));
  const std::vector<double> b = Frequencies(Solve(ApplyEffect(formats::ReadModelFile(files_->model), loose), so));
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) EXPECT_NEAR(a[i], b[i], 1e-12 * b[i]);
}

// Bad input names the file and line of the [[fe.part]] and what was expected.
class PartBadInput : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = testing::TempDir("part-bad-input");
    // Two DOFs (node 1 uz, node 2 uz): a 2-spring chain.
    Eigen::SparseMatrix<double> m(2, 2), k(2, 2), k3(3, 3), asym(2, 2), indefinite(2, 2);
    m.insert(0, 0) = 1.0, m.insert(1, 1) = 1.0;
    k.insert(0, 0) = 2.0, k.insert(1, 1) = 1.0, k.insert(0, 1) = -1.0, k.insert(1, 0) = -1.0;
    k3.insert(0, 0) = 1.0;
    asym.insert(0, 0) = 1.0, asym.insert(0, 1) = 0.5, asym.insert(1, 0) = -0.5, asym.insert(1, 1) = 1.0;
    indefinite.insert(0, 0) = 1.0, indefinite.insert(1, 1) = 1.0, indefinite.insert(0, 1) = 3.0, indefinite.insert(1, 0) = 3.0;
    formats::WriteMatrixMarket(dir_ / "M.mtx", m);
    formats::WriteMatrixMarket(dir_ / "K.mtx", k);
    formats::WriteMatrixMarket(dir_ / "K3.mtx", k3);
    formats::WriteMatrixMarket(dir_ / "Kasym.mtx", asym, false);
    formats::WriteMatrixMarket(dir_ / "Kneg.mtx", indefinite);
    testing::WriteText(dir_ / "dofs.csv", "node,dof\n1,3\n2,3\n");
  }
  std::string Error(const std::string& parts, const std::string& before = "") {
    const fs::path path = testing::WriteText(
        dir_ / "model.toml", before + "[fe]\nmass = \"M.mtx\"\ndofs = \"dofs.csv\"\n\n" + parts);
    try {
      formats::ReadModelFile(path);
    } catch (const InputError& e) {
      return e.what();
    }
    return "no error";
  }
  fs::path dir_;
};

TEST_F(PartBadInput, WrongSizeNamesTheLineAndTheSizes) {
  const std::string e = Error("[[fe.part]]\nname = \"J1\"\nstiffness = \"K3.mtx\"\n");
  EXPECT_NE(e.find("model.toml:5"), std::string::npos) << e;
  EXPECT_NE(e.find("K3.mtx is 3x3 but the [fe] DOF map has 2 rows"), std::string::npos) << e;
}

TEST_F(PartBadInput, NonSymmetricNamesTheEntry) {
  const std::string e = Error("[[fe.part]]\nname = \"J1\"\nstiffness = \"Kasym.mtx\"\n");
  EXPECT_NE(e.find("Kasym.mtx"), std::string::npos) << e;
  EXPECT_NE(e.find("symmetric"), std::string::npos) << e;
}

TEST_F(PartBadInput, IndefinitePartNamesTheLineAndTheDof) {
  const std::string e = Error("[[fe.part]]\nname = \"J1\"\nstiffness = \"K.mtx\"\n\n[[fe.part]]\nname = \"J2\"\nstiffness = \"Kneg.mtx\"\n");
  EXPECT_NE(e.find("model.toml:9"), std::string::npos) << e;
  EXPECT_NE(e.find("part 'J2' ("), std::string::npos) << e;
  EXPECT_NE(e.find("not positive semi-definite"), std::string::npos) << e;
  EXPECT_NE(e.find("node 2 uz"), std::string::npos) << e;
}

TEST_F(PartBadInput, NameClashWithASpringGroupOrABody) {
  const std::string body =
      "[[body]]\nname = \"joints\"\nmass = 1.0\ninertia = [1.0, 1.0, 1.0]\n\n";
  std::string e = Error("[[fe.part]]\nname = \"J1\"\ngroup = \"joints\"\nstiffness = \"K.mtx\"\n", body);
  EXPECT_NE(e.find("model.toml:10"), std::string::npos) << e;
  EXPECT_NE(e.find("part group name 'joints' is also a body"), std::string::npos) << e;
  const std::string spring =
      "[[spring]]\nname = \"s\"\ngroup = \"mounts\"\na = { node = 1 }\ndirection = [0.0, 0.0, 1.0]\nlaw = { linear = { k = 1.0 } }\n\n";
  e = Error("[[fe.part]]\nname = \"mounts\"\nstiffness = \"K.mtx\"\n", spring);
  EXPECT_NE(e.find("model.toml:12"), std::string::npos) << e;
  EXPECT_NE(e.find("part name 'mounts' is also a spring group"), std::string::npos) << e;
  e = Error("[[fe.part]]\nname = \"J1\"\nstiffness = \"K.mtx\"\n\n[[fe.part]]\nname = \"J1\"\nstiffness = \"K.mtx\"\n");
  EXPECT_NE(e.find("duplicate part name 'J1'"), std::string::npos) << e;
  e = Error("[[fe.part]]\nname = \"J1\"\n");
  EXPECT_NE(e.find("expected 'stiffness'"), std::string::npos) << e;
}

// A support spring alone (a singular part) and a model with [fe].stiffness absent are normal input.
TEST_F(PartBadInput, SingularPartsAreNormalInput) {
  Eigen::SparseMatrix<double> support(2, 2), link(2, 2);
  support.insert(0, 0) = 4.0;
  link.insert(0, 0) = 1.0, link.insert(1, 1) = 1.0, link.insert(0, 1) = -1.0, link.insert(1, 0) = -1.0;
  formats::WriteMatrixMarket(dir_ / "Ksupport.mtx", support);
  formats::WriteMatrixMarket(dir_ / "Klink.mtx", link);
  const fs::path path = testing::WriteText(dir_ / "ok.toml",
                                           "[fe]\nmass = \"M.mtx\"\ndofs = \"dofs.csv\"\n\n[[fe.part]]\nname = \"support\"\n"
                                           "stiffness = \"Ksupport.mtx\"\n\n[[fe.part]]\nname = \"link\"\nstiffness = \"Klink.mtx\"\n");
  const Solution s = Solve(formats::ReadModelFile(path));
  // Two unit masses, a spring of 4 to ground and one of 1 between them: λ = (6 ∓ √(4 + 16)) / 2.
  ASSERT_EQ(s.modes.modes.size(), 2u);
  EXPECT_NEAR(s.modes.modes[0].frequency_hz, std::sqrt((6.0 - std::sqrt(20.0)) / 2.0) / kTwoPi, 1e-12);
  EXPECT_NEAR(s.modes.modes[1].frequency_hz, std::sqrt((6.0 + std::sqrt(20.0)) / 2.0) / kTwoPi, 1e-12);
}

// A massless DOF that no stiffness holds is an error naming it.
TEST_F(PartBadInput, MasslessDofWithoutStiffnessIsNamed) {
  Eigen::SparseMatrix<double> m1(2, 2), ksup(2, 2);
  m1.insert(0, 0) = 1.0;
  ksup.insert(0, 0) = 1.0;
  formats::WriteMatrixMarket(dir_ / "M1.mtx", m1);
  formats::WriteMatrixMarket(dir_ / "K1.mtx", ksup);
  const fs::path path = testing::WriteText(dir_ / "loose.toml", "[fe]\nmass = \"M1.mtx\"\ndofs = \"dofs.csv\"\n\n"
                                                                "[[fe.part]]\nname = \"s\"\nstiffness = \"K1.mtx\"\n");
  try {
    Solve(formats::ReadModelFile(path));
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("DOF fe:2:uz has no mass and nothing holds it"), std::string::npos) << e.what();
  }
}

// The sparse solver's lowest frequencies follow a part factor smoothly on a fine frame (the 50 004
// DOFs of bench_diagnose_parts, λmax/λmin ~ 1e11): with σ just below zero the shift-invert solves
// are accurate to ε·λmax/λ only, and σ + 1/θ moved the lowest frequency at random by up to 1e-3
// between neighbouring factors (0.5 % stiffer came out 0.11 % lower here); the Rayleigh quotients
// are second-order accurate (noise ~2e-5 of the frequency, measured). Over 3.5 % of girder zone
// G3's factor the two lowest frequencies lie on a line (its curvature there < 1e-5 of them) within
// 1e-4 — a tenth of a σ at the diagnosis's 0.1 % floor.
TEST(FrameSolve, LowestFrequencyFollowsAPartFactorSmoothlyOnAFineFrame) {
  ema::testing::FrameSpec spec;
  spec.segments = 4166;
  spec.zones = 30;
  const ema::testing::FrameFiles files = ema::testing::WriteFrame(testing::TempDir("frame-smooth"), spec);
  ASSERT_EQ(files.dofs, 50004);
  const Model nominal = formats::ReadModelFile(files.model);
  SolveOptions options;
  options.max_modes = 20;
  options.sparse_threshold = 200;
  auto lowest = [&](double factor) {
    const Model m = ApplyEffect(
        nominal, {EffectKind::kStiffnessScale, EffectTarget::MemberOf("girders", "G3"), {{"factor", factor}}, std::nullopt, 0});
    const Solution s = Solve(m, options);
    EXPECT_TRUE(s.sparse);
    return std::vector<double>{s.modes.modes.at(0).frequency_hz, s.modes.modes.at(1).frequency_hz};
  };
  // Eight factors 0.5 % apart: each frequency within 1e-4 of the least-squares line through them.
  constexpr int kSteps = 8;
  Eigen::MatrixXd f(kSteps, 2);
  Eigen::VectorXd step(kSteps);
  for (int k = 0; k < kSteps; ++k) {
    step(k) = 0.005 * k;
    const std::vector<double> lowest_two = lowest(0.4 * (1.0 + step(k)));
    f(k, 0) = lowest_two[0];
    f(k, 1) = lowest_two[1];
  }
  Eigen::MatrixXd line(kSteps, 2);
  line.col(0).setOnes();
  line.col(1) = step;
  for (int j = 0; j < 2; ++j) {
    const Eigen::VectorXd fit = line.colPivHouseholderQr().solve(f.col(j));
    const Eigen::VectorXd off = f.col(j) - line * fit;
    EXPECT_GT(fit(1), 0.0) << "mode " << j << ": a stiffer zone, a higher frequency";
    EXPECT_LT(off.cwiseAbs().maxCoeff(), 1e-4 * f(0, j)) << "mode " << j << ": " << f.col(j).transpose();
  }
}

}  // namespace
}  // namespace ema::model
