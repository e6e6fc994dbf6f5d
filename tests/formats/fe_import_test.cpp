// `ema fe-import`'s readers and parts (formats/fe_import.hpp): CalculiX MATRIXSTORAGE files and
// Abaqus MATRIX INPUT files written by hand for a three-DOF spring chain whose parts are known
// exactly, a real ccx run when ccx is installed, and one bad file per check.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "ema/core/error.hpp"
#include "ema/formats/fe_import.hpp"
#include "ema/formats/matrix_market.hpp"
#include "ema/formats/model_file.hpp"
#include "tmp_file.hpp"

namespace ema::formats {
namespace {

namespace fs = std::filesystem;

// The chain: DOF 1 (node 1, x) on a ground spring C = 10, spring A = 100 between DOFs 1 and 2,
// spring B = 50 between DOFs 2 and 3. K_nominal upper triangle:
//   (1,1) 110  (1,2) -100  (2,2) 150  (2,3) -50  (3,3) 50
// Run "a": A × 0.5; run "b": B × 0.5. Then K_A = 100 [1 -1; -1 1] on DOFs 1-2, K_B = 50 [...] on
// DOFs 2-3, K_rest = diag(10, 0, 0). Mass diag(1, 2, 3).
constexpr const char* kDof = "1.1\n2.1\n3.1\n";
constexpr const char* kNominal = "1 1 1.1000000000000e+02\n1 2 -1.0000000000000e+02\n2 2 1.5000000000000e+02\n"
                                 "2 3 -5.0000000000000e+01\n3 3 5.0000000000000e+01\n";
constexpr const char* kRunA = "1 1 6.0000000000000e+01\n1 2 -5.0000000000000e+01\n2 2 1.0000000000000e+02\n"
                              "2 3 -5.0000000000000e+01\n3 3 5.0000000000000e+01\n";
constexpr const char* kRunB = "1 1 1.1000000000000e+02\n1 2 -1.0000000000000e+02\n2 2 1.2500000000000e+02\n"
                              "2 3 -2.5000000000000e+01\n3 3 2.5000000000000e+01\n";
constexpr const char* kMass = "1 1 1.0\n2 2 2.0\n3 3 3.0\n";

fs::path FeFolder(const std::string& name) {
  const fs::path dir = test::TmpFile("fe_import_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

void WriteFeText(const fs::path& path, const std::string& text) {
  std::ofstream out(path);
  out << text;
}

// A CalculiX job JOB in `dir`: JOB.sti, JOB.mas, JOB.dof.
FeRun FeJob(const fs::path& dir, const std::string& job, const std::string& sti, const std::string& dof = kDof,
          const std::string& mas = kMass) {
  WriteFeText(dir / (job + ".sti"), sti);
  WriteFeText(dir / (job + ".mas"), mas);
  WriteFeText(dir / (job + ".dof"), dof);
  return FeRunNamed((dir / job).string());
}

FePartInput FePart(const std::string& name, const FeRun& run, double scale = 0.5) {
  FePartInput p;
  p.name = name;
  p.run = run;
  p.scale = scale;
  return p;
}

Eigen::MatrixXd FullOfLower(const Eigen::SparseMatrix<double>& lower) {
  const Eigen::MatrixXd l = Eigen::MatrixXd(lower);
  Eigen::MatrixXd full = l + l.transpose();
  full.diagonal() = l.diagonal();
  return full;
}

// The message of the InputError `f` throws ("" when it throws none).
template <class F>
std::string FeInputErrorOf(F f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(ImportFeParts, SpringChainGivesTheExactParts) {
  const fs::path dir = FeFolder("chain");
  const FeRun nominal = FeJob(dir, "nominal", kNominal);
  const FeImport im = ImportFeParts(nominal, {FePart("A", FeJob(dir, "a", kRunA)), FePart("B", FeJob(dir, "b", kRunB))});
  ASSERT_EQ(im.dofs.size(), 3u);
  EXPECT_EQ(im.dofs[2], (FeDof{3, 1}));
  ASSERT_EQ(im.parts.size(), 2u);
  Eigen::MatrixXd ka(3, 3), kb(3, 3), rest(3, 3), m(3, 3);
  ka << 100, -100, 0, -100, 100, 0, 0, 0, 0;
  kb << 0, 0, 0, 0, 50, -50, 0, -50, 50;
  rest << 10, 0, 0, 0, 0, 0, 0, 0, 0;
  m << 1, 0, 0, 0, 2, 0, 0, 0, 3;
  EXPECT_EQ(FullOfLower(im.parts[0].stiffness), ka);
  EXPECT_EQ(FullOfLower(im.parts[1].stiffness), kb);
  EXPECT_EQ(FullOfLower(im.rest), rest);
  EXPECT_EQ(FullOfLower(im.mass), m);
  EXPECT_EQ(im.rest.nonZeros(), 1);  // the zeros of the difference are dropped
  EXPECT_EQ(im.parts[0].dof_count, 2);
  EXPECT_EQ(im.parts[1].dof_count, 2);
  EXPECT_DOUBLE_EQ(im.max_stiffness, 150.0);

  // Written and read back as a model: [fe] + [[fe.part]], K = K_rest + the parts.
  const fs::path out = dir / "out";
  fs::create_directories(out);
  FeImportWriteOptions w;
  w.group = "springs";
  w.uncertainty = 0.5;
  WriteFeImport(im, out / "fe.toml", w);
  for (const fs::path& f : FeImportOutputs(im, out / "fe.toml")) EXPECT_TRUE(fs::exists(f)) << f;
  const model::Model model = ReadModelFile(out / "fe.toml");
  ASSERT_EQ(model.fe.parts.size(), 2u);
  EXPECT_EQ(model.fe.parts[1].name, "B");
  EXPECT_EQ(model.fe.parts[1].group, "springs");
  EXPECT_DOUBLE_EQ(model.fe.parts[1].uncertainty, 0.5);
  EXPECT_EQ(Eigen::MatrixXd(*model.fe.parts[0].stiffness), ka);
  EXPECT_EQ(Eigen::MatrixXd(model.fe.stiffness), rest);
  EXPECT_EQ(Eigen::MatrixXd(model.fe.mass), m);
  ASSERT_EQ(model.fe.dofs.size(), 3u);
}

TEST(ImportFeParts, ScaleOtherThanAHalfDividesByOneMinusIt) {
  const fs::path dir = FeFolder("scale");
  // B × 2: (2,2) 200, (2,3) -100, (3,3) 100 → K_B = (K0 − K_s) / (1 − 2) = the same 50 [1 -1; -1 1].
  const FeImport im = ImportFeParts(
      FeJob(dir, "nominal", kNominal),
      {FePart("B", FeJob(dir, "b2", "1 1 110\n1 2 -100\n2 2 200\n2 3 -100\n3 3 100\n"), 2.0)});
  EXPECT_DOUBLE_EQ(im.parts[0].stiffness.coeff(1, 1), 50.0);
  EXPECT_DOUBLE_EQ(im.parts[0].stiffness.coeff(2, 1), -50.0);
  EXPECT_DOUBLE_EQ(im.rest.coeff(0, 0), 110.0);
  EXPECT_DOUBLE_EQ(im.rest.coeff(1, 1), 100.0);
}

// ---- the Abaqus route: the same chain, nodes 10, 20, 30, direction 1 ----

TEST(ImportFeParts, AbaqusMatrixInputInAnyTriangleGivesTheSameParts) {
  const fs::path dir = FeFolder("abaqus");
  // Nominal as the lower triangle, run A as the upper, run B in full (square).
  WriteFeText(dir / "nom_STIF1.mtx", "** nominal\n10,1, 10,1, 110.\n20,1, 10,1, -100.\n20,1, 20,1, 150.\n"
                               "30,1, 20,1, -50.\n30,1, 30,1, 50.\n");
  WriteFeText(dir / "nom_MASS1.mtx", "10,1, 10,1, 1.\n20,1, 20,1, 2.\n30,1, 30,1, 3.\n");
  WriteFeText(dir / "a_STIF1.mtx", "10,1, 10,1, 60.\n10,1, 20,1, -50.\n20,1, 20,1, 100.\n20,1, 30,1, -50.\n30,1, 30,1, 50.\n");
  WriteFeText(dir / "b_STIF1.mtx", "10,1, 10,1, 110.\n10,1, 20,1, -100.\n20,1, 10,1, -100.\n20,1, 20,1, 125.\n"
                             "20,1, 30,1, -25.\n30,1, 20,1, -25.\n30,1, 30,1, 25.\n");
  const FeRun nominal = FeRunNamed((dir / "nom_STIF1.mtx").string());
  ASSERT_EQ(nominal.code, FeRun::Code::kAbaqus);
  EXPECT_EQ(nominal.mass, dir / "nom_MASS1.mtx");
  const FeImport im = ImportFeParts(nominal, {FePart("A", FeRunNamed((dir / "a_STIF1.mtx").string())),
                                              FePart("B", FeRunNamed((dir / "b_STIF1.mtx").string()))});
  ASSERT_EQ(im.dofs.size(), 3u);
  EXPECT_EQ(im.dofs[0], (FeDof{10, 1}));
  Eigen::MatrixXd ka(3, 3), kb(3, 3);
  ka << 100, -100, 0, -100, 100, 0, 0, 0, 0;
  kb << 0, 0, 0, 0, 50, -50, 0, -50, 50;
  EXPECT_EQ(FullOfLower(im.parts[0].stiffness), ka);
  EXPECT_EQ(FullOfLower(im.parts[1].stiffness), kb);
  EXPECT_DOUBLE_EQ(im.rest.coeff(0, 0), 10.0);
  EXPECT_EQ(im.rest.nonZeros(), 1);
  EXPECT_DOUBLE_EQ(im.mass.coeff(2, 2), 3.0);

  // A part's own matrix (*MATRIX GENERATE, ELSET=): B directly, on two of the three DOFs.
  WriteFeText(dir / "B_elset.mtx", "20,1, 20,1, 50.\n30,1, 20,1, -50.\n30,1, 30,1, 50.\n");
  FePartInput b = FePart("B", FeRunNamed((dir / "B_elset.mtx").string()));
  b.direct = true;
  const FeImport direct = ImportFeParts(nominal, {b});
  EXPECT_EQ(FullOfLower(direct.parts[0].stiffness), kb);
  EXPECT_DOUBLE_EQ(direct.rest.coeff(1, 1), 100.0);
}

TEST(ImportFeParts, AbaqusTrianglesThatDisagreeAreNamedByLine) {
  const fs::path dir = FeFolder("abaqus_asym");
  WriteFeText(dir / "k.mtx", "10,1, 10,1, 110.\n10,1, 20,1, -100.\n20,1, 10,1, -90.\n20,1, 20,1, 150.\n");
  const std::string what = FeInputErrorOf([&] { ReadAbaqusMatrix(dir / "k.mtx"); });
  EXPECT_NE(what.find("k.mtx:"), std::string::npos) << what;
  EXPECT_NE(what.find("not symmetric"), std::string::npos) << what;
  EXPECT_NE(what.find("-100"), std::string::npos) << what;
  EXPECT_NE(what.find("-90"), std::string::npos) << what;
}

TEST(ImportFeParts, AbaqusPartMatrixOffTheNominalDofsIsNamedByLine) {
  const fs::path dir = FeFolder("abaqus_label");
  WriteFeText(dir / "nom_STIF1.mtx", "10,1, 10,1, 110.\n20,1, 10,1, -100.\n20,1, 20,1, 150.\n");
  WriteFeText(dir / "p.mtx", "10,1, 10,1, 1.\n40,2, 40,2, 1.\n");
  FePartInput p = FePart("P", FeRunNamed((dir / "p.mtx").string()));
  p.direct = true;
  const std::string what = FeInputErrorOf([&] { ImportFeParts(FeRunNamed((dir / "nom_STIF1.mtx").string()), {p}); });
  EXPECT_NE(what.find("p.mtx:2"), std::string::npos) << what;
  EXPECT_NE(what.find("40.2"), std::string::npos) << what;
}

// ---- one bad file per check ----

TEST(ImportFeParts, LowerTriangleEntryInACalculixFileIsNamedByLine) {  // symmetry
  const fs::path dir = FeFolder("lower");
  const std::string what = FeInputErrorOf([&] {
    ImportFeParts(FeJob(dir, "nominal", "1 1 110\n1 2 -100\n2 1 -99\n2 2 150\n2 3 -50\n3 3 50\n"),
                  {FePart("A", FeJob(dir, "a", kRunA))});
  });
  EXPECT_NE(what.find("nominal.sti:3"), std::string::npos) << what;
  EXPECT_NE(what.find("below the diagonal"), std::string::npos) << what;
}

TEST(ImportFeParts, PartNotPositiveSemiDefiniteIsNamedByFileAndRow) {
  const fs::path dir = FeFolder("psd");
  // Run b with (2,2) = 175 instead of 125: K_B(2,2) = (150 − 175) / 0.5 = −50.
  const std::string what = FeInputErrorOf([&] {
    ImportFeParts(FeJob(dir, "nominal", kNominal),
                  {FePart("A", FeJob(dir, "a", kRunA)),
                   FePart("B", FeJob(dir, "b", "1 1 110\n1 2 -100\n2 2 175\n2 3 -25\n3 3 25\n"))});
  });
  EXPECT_NE(what.find("b.sti, row 2 (DOF 2.1)"), std::string::npos) << what;
  EXPECT_NE(what.find("part 'B' is not positive semi-definite"), std::string::npos) << what;
  EXPECT_NE(what.find("1 eigenvalue below -tau"), std::string::npos) << what;
}

TEST(ImportFeParts, SlightlyIndefiniteRoundOffPassesThePsdCheck) {
  const fs::path dir = FeFolder("psd_roundoff");
  // K_A's coupling 1e-14 too large: an eigenvalue of about −1e-12, within τ = 1e-9 × 100.
  const FeImport im = ImportFeParts(
      FeJob(dir, "nominal", kNominal),
      {FePart("A", FeJob(dir, "a", "1 1 60\n1 2 -49.9999999999995\n2 2 100\n2 3 -50\n3 3 50\n"))});
  EXPECT_EQ(im.parts.size(), 1u);
}

TEST(ImportFeParts, OverlappingPartsAreNamedByRowAndParts) {
  const fs::path dir = FeFolder("overlap");
  // Two parts made from the same run: spring A counted twice, K_rest(1,1) = 110 − 200 < 0.
  const FeRun a = FeJob(dir, "a", kRunA);
  const std::string what = FeInputErrorOf([&] {
    ImportFeParts(FeJob(dir, "nominal", kNominal), {FePart("A", a), FePart("A2", a)});
  });
  EXPECT_NE(what.find("nominal.sti, row 1 (DOF 1.1)"), std::string::npos) << what;
  EXPECT_NE(what.find("the parts overlap"), std::string::npos) << what;
  EXPECT_NE(what.find("A ("), std::string::npos) << what;
  EXPECT_NE(what.find("A2 ("), std::string::npos) << what;
}

TEST(ImportFeParts, DofMapThatDiffersBetweenRunsIsNamedByLine) {
  const fs::path dir = FeFolder("dofmap");
  const FeRun nominal = FeJob(dir, "nominal", kNominal);
  std::string what = FeInputErrorOf([&] { ImportFeParts(nominal, {FePart("A", FeJob(dir, "a", kRunA, "1.1\n3.1\n2.1\n"))}); });
  EXPECT_NE(what.find("a.dof:2"), std::string::npos) << what;
  EXPECT_NE(what.find("DOF 3.1 where the nominal run's DOF map"), std::string::npos) << what;
  EXPECT_NE(what.find("nominal.dof:2) has 2.1"), std::string::npos) << what;
  // One DOF fewer (a node clamped in one run only).
  what = FeInputErrorOf([&] { ImportFeParts(nominal, {FePart("A", FeJob(dir, "a2", "1 1 60\n", "1.1\n"))}); });
  EXPECT_NE(what.find("a2.dof: 1 DOFs, the nominal run's DOF map"), std::string::npos) << what;
}

TEST(ImportFeParts, RunWithNothingChangedIsAnError) {
  const fs::path dir = FeFolder("unchanged");
  const std::string what =
      FeInputErrorOf([&] { ImportFeParts(FeJob(dir, "nominal", kNominal), {FePart("A", FeJob(dir, "a", kNominal))}); });
  EXPECT_NE(what.find("a.sti: part 'A': this run's stiffness is the nominal one"), std::string::npos) << what;
}

TEST(ImportFeParts, PartOffTheNominalPatternIsNamedByRow) {
  const fs::path dir = FeFolder("pattern");
  // Run a couples DOFs 1 and 3, which the nominal assembly does not.
  const std::string what = FeInputErrorOf([&] {
    ImportFeParts(FeJob(dir, "nominal", kNominal),
                  {FePart("A", FeJob(dir, "a", "1 1 60\n1 2 -50\n1 3 -1\n2 2 100\n2 3 -50\n3 3 50\n"))});
  });
  EXPECT_NE(what.find("a.sti, row 3 (DOF 3.1)"), std::string::npos) << what;
  EXPECT_NE(what.find("where the nominal stiffness has none"), std::string::npos) << what;
}

TEST(ReadCalculixMatrix, BadLinesAreNamedByFileAndLine) {
  const fs::path dir = FeFolder("bad_lines");
  const auto error_of = [&](const std::string& text) {
    WriteFeText(dir / "k.sti", text);
    return FeInputErrorOf([&] { ReadCalculixMatrix(dir / "k.sti", 3); });
  };
  std::string what = error_of("1 1 110\n1 2\n");  // truncated line
  EXPECT_NE(what.find("k.sti:2: expected 'row column value'"), std::string::npos) << what;
  what = error_of("1 1 110\n1 2 -1.0e+0x\n");
  EXPECT_NE(what.find("k.sti:2: expected 'row column value'"), std::string::npos) << what;
  what = error_of("1 1 110\n\n2 4 1\n");  // outside the DOF map
  EXPECT_NE(what.find("k.sti:3: entry (2, 4) outside the 3 DOFs"), std::string::npos) << what;
  what = error_of("1 1 110\n1 2 1\n1 2 1\n");
  EXPECT_NE(what.find("k.sti:3: entry given twice"), std::string::npos) << what;
  what = error_of("");
  EXPECT_NE(what.find("k.sti: no entry"), std::string::npos) << what;
  what = error_of(std::string("1 1 1\n1 2 \0 3\n", 14));
  EXPECT_NE(what.find("k.sti:2: binary data"), std::string::npos) << what;
}

TEST(ReadCalculixDofs, BadLinesAreNamedByFileAndLine) {
  const fs::path dir = FeFolder("bad_dofs");
  const auto error_of = [&](const std::string& text) {
    WriteFeText(dir / "j.dof", text);
    return FeInputErrorOf([&] { ReadCalculixDofs(dir / "j.dof"); });
  };
  std::string what = error_of("1.1\n17x3\n");
  EXPECT_NE(what.find("j.dof:2: expected 'node.direction'"), std::string::npos) << what;
  what = error_of("1.1\n2.7\n");
  EXPECT_NE(what.find("j.dof:2: DOF '2.7': direction 7 outside 1..6"), std::string::npos) << what;
  what = error_of("1.1\n2.1\n1.1\n");
  EXPECT_NE(what.find("j.dof:3: DOF 1.1 listed twice (first on line 1)"), std::string::npos) << what;
  EXPECT_NE(FeInputErrorOf([&] { ReadCalculixDofs(dir / "missing.dof"); }).find("missing.dof: cannot open"), std::string::npos);
}

// The chain's deck: the ground spring C on node 1, A between nodes 1-2, B between 2-3.
constexpr const char* kChainDeck =
    "*ELEMENT, TYPE=SPRINGA, ELSET=C\n1, 1\n*ELEMENT, TYPE=T3D2, ELSET=A\n2, 1, 2\n*ELEMENT, TYPE=T3D2, ELSET=B\n3, 2, 3\n"
    "*ELSET, ELSET=AB\nA, B\n";

TEST(ImportFeParts, HandDeckChecksEachPartOnItsOwnElements) {
  const fs::path dir = FeFolder("hand_deck");
  WriteFeText(dir / "chain.inp", kChainDeck);
  const FeElementSets sets = ReadInpElementSets(dir / "chain.inp");
  const FeRun nominal = FeJob(dir, "nominal", kNominal);
  const FeRun a = FeJob(dir, "a", kRunA), b = FeJob(dir, "b", kRunB);
  // Right: A from run a, B from run b; K_rest = the ground spring, on element C.
  const FeImport im = ImportFeParts(nominal, {FePart("A", a), FePart("B", b)}, {}, {}, &sets);
  EXPECT_EQ(FullOfLower(im.rest)(0, 0), 10.0);
  EXPECT_EQ(im.rest.nonZeros(), 1);
  // Part A made from B's run: its stiffness lies on B's element (nodes 2-3), off A's.
  std::string what = FeInputErrorOf([&] { ImportFeParts(nominal, {FePart("A", b)}, {}, {}, &sets); });
  EXPECT_NE(what.find("b.sti, row 3 (DOF 3.1): part 'A' has stiffness at (3.1, 2.1)"), std::string::npos) << what;
  EXPECT_NE(what.find("off its own elements (*ELSET A of"), std::string::npos) << what;
  // Part AB (both springs) from run a, which changed only A: K_rest keeps B's stiffness, where
  // only AB's elements are.
  what = FeInputErrorOf([&] { ImportFeParts(nominal, {FePart("AB", a)}, {}, {}, &sets); });
  EXPECT_NE(what.find("nominal.sti, row 2 (DOF 2.1): K_rest = K_nominal - sum of parts keeps"), std::string::npos) << what;
  EXPECT_NE(what.find("did not change all of its elements"), std::string::npos) << what;
  // A part without an element set of its name, and two parts sharing an element.
  what = FeInputErrorOf([&] { ImportFeParts(nominal, {FePart("D", a)}, {}, {}, &sets); });
  EXPECT_NE(what.find("chain.inp: no element set 'D'"), std::string::npos) << what;
  what = FeInputErrorOf([&] { ImportFeParts(nominal, {FePart("A", a), FePart("AB", b)}, {}, {}, &sets); });
  EXPECT_NE(what.find("in the sets of two parts, 'A' and 'AB'"), std::string::npos) << what;
}

// ---- a real CalculiX run ----

// Two C3D8 bricks stacked in z (nodes 1-4 clamped): A (E = 100) below, B (E = 50) above. B is A
// moved up by one, so B's block on its top face (nodes 9-12) is exactly half A's on its top face
// (nodes 5-8), and K_A lies on nodes 5-8 only.
std::string CcxDeck(double e_a, double e_b) {
  std::string d = "*NODE\n";
  const double xy[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  for (int layer = 0; layer < 3; ++layer)
    for (int k = 0; k < 4; ++k)
      d += std::to_string(4 * layer + k + 1) + "," + std::to_string(xy[k][0]) + "," + std::to_string(xy[k][1]) + "," +
           std::to_string(layer) + "\n";
  d += "*ELEMENT,TYPE=C3D8,ELSET=A\n1,1,2,3,4,5,6,7,8\n*ELEMENT,TYPE=C3D8,ELSET=B\n2,5,6,7,8,9,10,11,12\n";
  d += "*BOUNDARY\n1,1,3\n2,1,3\n3,1,3\n4,1,3\n";
  d += "*MATERIAL,NAME=MA\n*ELASTIC\n" + std::to_string(e_a) + ",0.3\n*DENSITY\n1.\n";
  d += "*MATERIAL,NAME=MB\n*ELASTIC\n" + std::to_string(e_b) + ",0.3\n*DENSITY\n1.\n";
  d += "*SOLID SECTION,ELSET=A,MATERIAL=MA\n*SOLID SECTION,ELSET=B,MATERIAL=MB\n";
  d += "*STEP\n*FREQUENCY,SOLVER=MATRIXSTORAGE\n4\n*END STEP\n";
  return d;
}

TEST(ImportFeParts, RealCalculixRunGivesEachElementSetItsOwnStiffness) {
  if (std::system("command -v ccx > /dev/null 2>&1") != 0) GTEST_SKIP() << "CalculiX (ccx) not installed";
  const fs::path dir = FeFolder("ccx");
  const std::vector<std::pair<std::string, std::string>> jobs = {
      {"nominal", CcxDeck(100, 50)}, {"a", CcxDeck(50, 50)}, {"b", CcxDeck(100, 25)}};
  for (const auto& [job, deck] : jobs) {
    WriteFeText(dir / (job + ".inp"), deck);
    const std::string cmd = "cd '" + dir.string() + "' && OMP_NUM_THREADS=1 ccx -i " + job + " > " + job + ".log 2>&1";
    ASSERT_EQ(std::system(cmd.c_str()), 0);
    ASSERT_TRUE(fs::exists(dir / (job + ".sti"))) << job;
  }
  const FeImport im = ImportFeParts(FeRunNamed((dir / "nominal").string()),
                                    {FePart("A", FeRunNamed((dir / "a").string())),
                                     FePart("B", FeRunNamed((dir / "b.inp").string()))});
  // 8 free nodes × 3, node by node ascending.
  ASSERT_EQ(im.dofs.size(), 24u);
  EXPECT_EQ(im.dofs.front(), (FeDof{5, 1}));
  EXPECT_EQ(im.dofs.back(), (FeDof{12, 3}));
  EXPECT_EQ(im.parts[0].dof_count, 12);  // A: its free top face
  EXPECT_EQ(im.parts[1].dof_count, 24);
  for (int c = 0; c < im.parts[0].stiffness.outerSize(); ++c)
    for (Eigen::SparseMatrix<double>::InnerIterator it(im.parts[0].stiffness, c); it; ++it) {
      EXPECT_LE(im.dofs[static_cast<std::size_t>(it.row())].node, 8);
      EXPECT_LE(im.dofs[static_cast<std::size_t>(c)].node, 8);
    }
  // All the stiffness is in the two parts.
  EXPECT_LT(FullOfLower(im.rest).cwiseAbs().maxCoeff(), 1e-11 * im.max_stiffness);
  const Eigen::MatrixXd ka = FullOfLower(im.parts[0].stiffness), kb = FullOfLower(im.parts[1].stiffness);
  const Eigen::MatrixXd top_a = ka.topLeftCorner(12, 12), top_b = kb.bottomRightCorner(12, 12);
  EXPECT_GT(top_a.cwiseAbs().maxCoeff(), 1.0);
  EXPECT_LT((top_b - 0.5 * top_a).cwiseAbs().maxCoeff(), 1e-10 * top_a.cwiseAbs().maxCoeff());
  // The consistent mass (density 1, unit cubes): per direction, the sum over the free nodes' block
  // is B's whole mass, 1, plus A's top face's share, the integral of ζ² over the cube, 1/3.
  EXPECT_EQ(im.mass.rows(), 24);
  EXPECT_NEAR(FullOfLower(im.mass).sum() / 3.0, 4.0 / 3.0, 1e-9);
}

// The same two bricks with the deck's element sets: each part on its own element's DOFs.
fs::path CcxJobs(const std::string& name, const std::vector<std::pair<std::string, std::string>>& jobs) {
  const fs::path dir = FeFolder(name);
  for (const auto& [job, deck] : jobs) {
    WriteFeText(dir / (job + ".inp"), deck);
    const std::string cmd = "cd '" + dir.string() + "' && OMP_NUM_THREADS=1 ccx -i " + job + " > " + job + ".log 2>&1";
    if (std::system(cmd.c_str()) != 0 || !fs::exists(dir / (job + ".sti"))) ADD_FAILURE() << "ccx failed on " << job;
  }
  return dir;
}

TEST(ImportFeParts, DeckElementSetsPlaceEachPartOnItsOwnElements) {
  if (std::system("command -v ccx > /dev/null 2>&1") != 0) GTEST_SKIP() << "CalculiX (ccx) not installed";
  const fs::path dir = CcxJobs("ccx_deck", {{"nominal", CcxDeck(100, 50)}, {"a", CcxDeck(50, 50)}, {"b", CcxDeck(100, 25)}});
  const FeElementSets sets = ReadInpElementSets(dir / "nominal.inp");
  ASSERT_EQ(sets.nodes.size(), 2u);
  ASSERT_NE(sets.Find("a"), nullptr);  // set names compare in any case
  EXPECT_EQ(sets.Find("B")->size(), 1u);
  EXPECT_EQ(sets.nodes[1].front(), 5);
  const FeImport im = ImportFeParts(FeRunNamed((dir / "nominal").string()),
                                    {FePart("A", FeRunNamed((dir / "a").string())), FePart("B", FeRunNamed((dir / "b").string()))},
                                    {}, {}, &sets);
  EXPECT_EQ(im.parts[0].dof_count, 12);
  EXPECT_EQ(im.parts[0].largest_dropped, 0.0);  // off its element, the difference is exactly zero
  EXPECT_EQ(im.rest.nonZeros(), 0);             // every element is in a part: K_rest's round-off is zeroed
}

TEST(ImportFeParts, PartWhoseRunChangedOtherElementsIsNamedByFileAndRow) {
  if (std::system("command -v ccx > /dev/null 2>&1") != 0) GTEST_SKIP() << "CalculiX (ccx) not installed";
  // Part A's run halves both materials: K_A then holds B's element too.
  const fs::path dir = CcxJobs("ccx_offset", {{"nominal", CcxDeck(100, 50)}, {"a", CcxDeck(50, 25)}});
  const FeElementSets sets = ReadInpElementSets(dir / "nominal.inp");
  const std::string what = FeInputErrorOf([&] {
    ImportFeParts(FeRunNamed((dir / "nominal").string()), {FePart("A", FeRunNamed((dir / "a").string()))}, {}, {}, &sets);
  });
  EXPECT_NE(what.find("a.sti, row "), std::string::npos) << what;
  EXPECT_NE(what.find("part 'A' has stiffness at ("), std::string::npos) << what;
  EXPECT_NE(what.find("off its own elements (*ELSET A of"), std::string::npos) << what;
}

TEST(ImportFeParts, PartWhoseRunMissedSomeOfItsElementsLeavesKRestOffTheRest) {
  if (std::system("command -v ccx > /dev/null 2>&1") != 0) GTEST_SKIP() << "CalculiX (ccx) not installed";
  // Part AB is both elements (an *ELSET of the two sets), but its run halves only A's material:
  // K_rest keeps B's stiffness, where only the part's elements are.
  std::string deck = CcxDeck(100, 50);
  deck.insert(deck.find("*BOUNDARY"), "*ELSET, ELSET=AB\nA, B\n");
  const fs::path dir = CcxJobs("ccx_missed", {{"nominal", deck}, {"ab", CcxDeck(50, 50)}});
  const FeElementSets sets = ReadInpElementSets(dir / "nominal.inp");
  ASSERT_NE(sets.Find("AB"), nullptr);
  EXPECT_EQ(sets.Find("AB")->size(), 2u);
  const std::string what = FeInputErrorOf([&] {
    ImportFeParts(FeRunNamed((dir / "nominal").string()), {FePart("AB", FeRunNamed((dir / "ab").string()))}, {}, {},
                  &sets);
  });
  EXPECT_NE(what.find("nominal.sti, row "), std::string::npos) << what;
  EXPECT_NE(what.find("K_rest = K_nominal - sum of parts keeps"), std::string::npos) << what;
  EXPECT_NE(what.find("did not change all of its elements"), std::string::npos) << what;
}

TEST(ReadInpElementSets, BadDecksAreNamedByFileAndLine) {
  const fs::path dir = FeFolder("bad_deck");
  const auto error_of = [&](const std::string& text) {
    WriteFeText(dir / "d.inp", text);
    return FeInputErrorOf([&] { ReadInpElementSets(dir / "d.inp"); });
  };
  std::string what = error_of("*NODE\n1,0,0,0\n*ELEMENT, TYPE=C3D8, ELSET=X\n1, 2, 3,\n4, x\n");
  EXPECT_NE(what.find("d.inp:5: *ELEMENT data"), std::string::npos) << what;
  what = error_of("*ELEMENT, TYPE=T3D2\n1, 1, 2\n1, 2, 3\n");
  EXPECT_NE(what.find("d.inp:3: element 1 defined twice"), std::string::npos) << what;
  what = error_of("*ELEMENT, TYPE=T3D2\n1, 1, 2\n*ELSET, ELSET=S\n1, 7\n");
  EXPECT_NE(what.find("d.inp:4: *ELSET S: element 7 is not defined"), std::string::npos) << what;
  what = error_of("*INCLUDE, INPUT=mesh.inp\n");
  EXPECT_NE(what.find("d.inp:1: *INCLUDE is not followed"), std::string::npos) << what;
  // A record continued over two lines, *ELSET GENERATE: read.
  WriteFeText(dir / "ok.inp", "** comment\n*ELEMENT, TYPE=C3D20, ELSET=J\n1, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15,\n"
                           "16, 17, 18, 19, 20\n*element, type=T3D2\n2, 20, 21\n3, 21, 22\n*ELSET, ELSET=G, GENERATE\n1, 3, 2\n");
  const FeElementSets ok = ReadInpElementSets(dir / "ok.inp");
  ASSERT_EQ(ok.nodes.size(), 3u);
  EXPECT_EQ(ok.nodes[0].size(), 20u);
  EXPECT_EQ(*ok.Find("g"), (std::vector<int>{0, 2}));
  EXPECT_EQ(ok.Find("J")->size(), 1u);
  EXPECT_EQ(ok.Find("nope"), nullptr);
}

}  // namespace
}  // namespace ema::formats
