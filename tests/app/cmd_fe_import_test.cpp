// `ema fe-import` end to end (docs/fe-parts.md, docs/cli.md): a hand-written CalculiX spring
// chain imported into a model that `ema model` solves; bad input names the file and row (exit 1,
// nothing on stdout); bad usage exits 2; the outputs never replace an input. The readers and every
// check on their own: tests/formats/fe_import_test.cpp.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "ema/formats/matrix_market.hpp"
#include "test_files.hpp"

namespace ema {
namespace {

namespace fs = std::filesystem;
using test::RunEma;
using test::Slurp;

fs::path FeImportDir(const std::string& name) {
  const fs::path dir = fs::path(EMA_TEST_TMP_DIR) / ("fe-import-cli-" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

void WriteFeImportText(const fs::path& path, const std::string& text) {
  std::ofstream out(path);
  out << text;
}

// The three-DOF chain of tests/formats/fe_import_test.cpp: ground spring 10 on DOF 1, spring A =
// 100 between DOFs 1-2, B = 50 between 2-3; runs a (A × 0.5) and b (B × 0.5); unit masses.
void WriteChain(const fs::path& dir, const std::string& run_b_sti = "1 1 110\n1 2 -100\n2 2 125\n2 3 -25\n3 3 25\n") {
  for (const char* job : {"nominal", "a", "b"}) {
    WriteFeImportText(dir / (std::string(job) + ".dof"), "1.1\n2.1\n3.1\n");
    WriteFeImportText(dir / (std::string(job) + ".mas"), "1 1 1\n2 2 1\n3 3 1\n");
  }
  WriteFeImportText(dir / "nominal.sti", "1 1 110\n1 2 -100\n2 2 150\n2 3 -50\n3 3 50\n");
  WriteFeImportText(dir / "a.sti", "1 1 60\n1 2 -50\n2 2 100\n2 3 -50\n3 3 50\n");
  WriteFeImportText(dir / "b.sti", run_b_sti);
}

std::string In(const fs::path& dir, const std::string& name) { return "'" + (dir / name).string() + "'"; }

TEST(FeImportCli, ChainImportsIntoAModelThatSolves) {
  const fs::path dir = FeImportDir("chain");
  WriteChain(dir);
  fs::create_directories(dir / "model");
  ASSERT_EQ(RunEma("fe-import --nominal " + In(dir, "nominal") + " --part A=" + In(dir, "a") + " --part B=" +
                       In(dir, "b.sti") + ":0.5 --group springs --uncertainty 0.3 -o " + In(dir, "model/fe.toml"),
                   dir),
            0)
      << Slurp(dir / "stderr.txt");
  const std::string out = Slurp(dir / "stdout.txt");
  EXPECT_NE(out.find("3 DOFs"), std::string::npos) << out;
  EXPECT_NE(out.find("part A"), std::string::npos) << out;
  const std::string toml = Slurp(dir / "model/fe.toml");
  EXPECT_NE(toml.find("group = \"springs\""), std::string::npos) << toml;
  EXPECT_NE(toml.find("uncertainty = 0.3"), std::string::npos) << toml;
  const Eigen::SparseMatrix<double> kb = formats::ReadMatrixMarket(dir / "model/K_B.mtx");
  EXPECT_EQ(kb.coeff(1, 1), 50.0);
  EXPECT_EQ(kb.coeff(2, 1), -50.0);
  EXPECT_EQ(kb.coeff(1, 2), -50.0);  // symmetric file, read in full
  EXPECT_EQ(kb.coeff(0, 0), 0.0);
  const Eigen::SparseMatrix<double> rest = formats::ReadMatrixMarket(dir / "model/K_rest.mtx");
  EXPECT_EQ(rest.nonZeros(), 1);
  EXPECT_EQ(rest.coeff(0, 0), 10.0);
  EXPECT_EQ(Slurp(dir / "model/dofs.csv"), "node,dof\n1,1\n2,1\n3,1\n");
  // The model solves: K = [110 -100 0; -100 150 -50; 0 -50 50], M = I.
  ASSERT_EQ(RunEma("model " + In(dir, "model/fe.toml") + " -o " + In(dir, "modes.unv") + " --json " +
                       In(dir, "modes.json"),
                   dir),
            0)
      << Slurp(dir / "stderr.txt");
  EXPECT_NE(Slurp(dir / "stdout.txt").find("3 modes"), std::string::npos) << Slurp(dir / "stdout.txt");
}

TEST(FeImportCli, PartNotPositiveSemiDefiniteExitsOneNamingFileAndRow) {
  const fs::path dir = FeImportDir("psd");
  WriteChain(dir, "1 1 110\n1 2 -100\n2 2 175\n2 3 -25\n3 3 25\n");
  EXPECT_EQ(RunEma("fe-import --nominal " + In(dir, "nominal") + " --part A=" + In(dir, "a") + " --part B=" +
                       In(dir, "b") + " -o " + In(dir, "fe.toml"),
                   dir),
            1);
  EXPECT_EQ(Slurp(dir / "stdout.txt"), "");
  const std::string err = Slurp(dir / "stderr.txt");
  EXPECT_NE(err.find("b.sti, row 2 (DOF 2.1): part 'B' is not positive semi-definite"), std::string::npos) << err;
  EXPECT_FALSE(fs::exists(dir / "fe.toml"));
  EXPECT_FALSE(fs::exists(dir / "K_A.mtx"));  // nothing is written before every check passed
}

TEST(FeImportCli, BadUsageExitsTwo) {
  const fs::path dir = FeImportDir("usage");
  WriteChain(dir);
  const std::string nominal = " --nominal " + In(dir, "nominal");
  EXPECT_EQ(RunEma("fe-import" + nominal + " -o " + In(dir, "fe.toml"), dir), 2);  // no part
  EXPECT_NE(Slurp(dir / "stderr.txt").find("no part"), std::string::npos);
  EXPECT_EQ(RunEma("fe-import" + nominal + " --part A=" + In(dir, "a") + " --part A=" + In(dir, "b") + " -o " +
                       In(dir, "fe.toml"),
                   dir),
            2);
  EXPECT_NE(Slurp(dir / "stderr.txt").find("part 'A' given twice"), std::string::npos);
  EXPECT_EQ(RunEma("fe-import" + nominal + " --part A=" + In(dir, "a") + ":1 -o " + In(dir, "fe.toml"), dir), 2);
  EXPECT_NE(Slurp(dir / "stderr.txt").find("positive and not 1"), std::string::npos);
  EXPECT_EQ(RunEma("fe-import" + nominal + " --part 'K/1'=" + In(dir, "a") + " -o " + In(dir, "fe.toml"), dir), 2);
  EXPECT_EQ(RunEma("fe-import --help", dir), 0);
  EXPECT_NE(Slurp(dir / "stdout.txt").find("--part-matrix"), std::string::npos);
}

TEST(FeImportCli, OutputsNeverReplaceAnInput) {
  const fs::path dir = FeImportDir("guard");
  WriteChain(dir);
  // A part's own matrix in the output folder, named as a written part would be: refused, untouched.
  WriteFeImportText(dir / "K_A.mtx", "10,1, 10,1, 50.\n");
  const std::string before = Slurp(dir / "K_A.mtx");
  EXPECT_EQ(RunEma("fe-import --nominal " + In(dir, "nominal") + " --part A=" + In(dir, "a") + " --part-matrix B=" +
                       In(dir, "K_A.mtx") + " -o " + In(dir, "fe.toml"),
                   dir),
            2);
  EXPECT_NE(Slurp(dir / "stderr.txt").find("K_A.mtx"), std::string::npos) << Slurp(dir / "stderr.txt");
  EXPECT_EQ(Slurp(dir / "K_A.mtx"), before);
}

}  // namespace
}  // namespace ema
