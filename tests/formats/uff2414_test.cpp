// Dataset 2414 (FE analysis results) read as model modes: the shared files that hold normal
// modes, one written here with known values, and `ema correlate` against it.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "ema/core/error.hpp"
#include "ema/formats/io.hpp"

namespace ema::formats {
namespace {

namespace fs = std::filesystem;
const fs::path kData = fs::path(EMA_REAL_DATA_DIR) / "uff";

int IndexOf(const ModeSet& set, Dof dof) {
  for (size_t i = 0; i < set.dofs.size(); ++i)
    if (set.dofs[i] == dof) return static_cast<int>(i);
  return -1;
}

TEST(Uff2414, PermasNormalModesWithGeometry) {
  // 10 normal modes (6 real values per node) after a 2411 node table, as Permas writes them.
  const ModeSet set = ReadModeSet(kData / "pyuff" / "2411 and 2414.uff");
  ASSERT_EQ(set.modes.size(), 10u);
  EXPECT_DOUBLE_EQ(set.modes[0].frequency_hz, 9.56363e-01);  // record 12 field 2, as written
  EXPECT_EQ(set.modes[0].damping_ratio, 0.0);
  EXPECT_FALSE(set.geometry.empty());  // the 2411 nodes
  // Node 1 of mode 1: -4.37263E-18 -8.53725E-18 -7.08571E-01 -4.18149E-02 1.00000E+00 -0.00000E+00
  const int z = IndexOf(set, {1, 3}), rx = IndexOf(set, {1, 4}), ry = IndexOf(set, {1, 5});
  ASSERT_GE(z, 0);
  ASSERT_GE(ry, 0);
  EXPECT_DOUBLE_EQ(set.modes[0].shape[z].real(), -7.08571e-01);
  EXPECT_DOUBLE_EQ(set.modes[0].shape[rx].real(), -4.18149e-02);
  EXPECT_DOUBLE_EQ(set.modes[0].shape[ry].real(), 1.0);
  EXPECT_EQ(set.modes[0].shape[z].imag(), 0.0);
}

TEST(Uff2414, ComplexValuedNormalModeAndFilesWithoutModes) {
  // ufffiles.jl: one normal mode stored as complex single precision (data type 5), 3 values per node.
  const ModeSet set = ReadModeSet(kData / "ufffiles-jl" / "dataset2414_node.unv");
  ASSERT_EQ(set.modes.size(), 1u);
  EXPECT_DOUBLE_EQ(set.modes[0].frequency_hz, 2.33832e+04);
  const int x = IndexOf(set, {3992, 1}), y = IndexOf(set, {3992, 2});
  ASSERT_GE(x, 0);
  EXPECT_DOUBLE_EQ(set.modes[0].shape[x].real(), 1.95655e-02);
  EXPECT_DOUBLE_EQ(set.modes[0].shape[y].real(), 1.30354e+01);
  // Static displacements, temperatures and element data are analysis results but not modes.
  EXPECT_THROW(ReadModeSet(kData / "pyuff" / "simcenter_exported_result.uff"), InputError);
  EXPECT_THROW(ReadModeSet(kData / "ufffiles-jl" / "dataset2414_elt.unv"), InputError);
}

// Writes a dataset 2414 normal mode the way Simcenter/NX does (real single precision, 3 values
// per node, nodes 1..3).
void Write2414(std::ostream& out, int mode, double f_hz, const std::vector<std::array<double, 3>>& values) {
  char line[128];
  out << "    -1\n  2414\n         " << mode << "\nMode " << mode << "\n         1\nNONE\nNONE\nNONE\nNONE\nNONE\n";
  out << "         1         2         2         8         2         3\n";
  std::snprintf(line, sizeof line, "         1         0         1         0         1%10d         0         0\n", mode);
  out << line << "         0         0\n";
  std::snprintf(line, sizeof line, "%13.5E%13.5E%13.5E%13.5E%13.5E%13.5E\n", 0.0, f_hz, 0.0, 1.0, 0.0, 0.0);
  out << line;
  std::snprintf(line, sizeof line, "%13.5E%13.5E%13.5E%13.5E%13.5E%13.5E\n", 0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
  out << line;
  for (size_t n = 0; n < values.size(); ++n) {
    std::snprintf(line, sizeof line, "%10zu\n%13.5E%13.5E%13.5E\n", n + 1, values[n][0], values[n][1], values[n][2]);
    out << line;
  }
  out << "    -1\n";
}

TEST(Uff2414, CorrelateReadsFeModesExportedAs2414) {
  const fs::path dir = fs::path(EMA_TEST_TMP_DIR) / "uff2414";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::vector<std::array<double, 3>> m1 = {{0, 0, 0.5}, {0, 0, 1.0}, {0, 0, 0.7}};
  const std::vector<std::array<double, 3>> m2 = {{0, 0, 1.0}, {0, 0, -0.2}, {0, 0, -0.9}};
  {
    std::ofstream out(dir / "fe.unv");
    Write2414(out, 1, 12.5, m1);
    Write2414(out, 2, 31.25, m2);
  }
  const ModeSet fe = ReadModeSet(dir / "fe.unv");
  ASSERT_EQ(fe.modes.size(), 2u);
  ASSERT_EQ(fe.dofs.size(), 3u);  // only Z is non-zero
  EXPECT_EQ(fe.dofs[1], (Dof{2, 3}));
  EXPECT_DOUBLE_EQ(fe.modes[1].frequency_hz, 31.25);
  EXPECT_DOUBLE_EQ(fe.modes[1].shape[2].real(), -0.9);

  // Test modes (dataset 55) 2 % above the FE modes with the same shapes, complex-scaled.
  ModeSet test;
  test.dofs = fe.dofs;
  for (int r = 0; r < 2; ++r) {
    Mode m;
    m.frequency_hz = fe.modes[r].frequency_hz * 1.02;
    m.damping_ratio = 0.01;
    m.pole = FrequencyAndDampingToPole(m.frequency_hz, m.damping_ratio);
    m.shape = fe.modes[r].shape * std::complex<double>(0.3, -0.4);
    test.modes.push_back(m);
  }
  WriteModeSet(dir / "test.unv", test);
  const std::string cmd = std::string("\"") + EMA_EXECUTABLE + "\" correlate \"" + (dir / "test.unv").string() + "\" \"" +
                          (dir / "fe.unv").string() + "\" --json \"" + (dir / "corr.json").string() + "\" > \"" +
                          (dir / "out.txt").string() + "\" 2>&1";
  ASSERT_EQ(std::system(cmd.c_str()), 0);
  std::ifstream in(dir / "corr.json");
  const auto j = nlohmann::json::parse(in);
  ASSERT_EQ(j["pairs"].size(), 2u);
  for (int r = 0; r < 2; ++r) {
    EXPECT_EQ(j["pairs"][r]["test_mode"], r + 1);
    EXPECT_EQ(j["pairs"][r]["model_mode"], r + 1);
    EXPECT_NEAR(j["pairs"][r]["mac"].get<double>(), 1.0, 1e-9);  // same shape up to a complex factor
    // agreement = 100 (1 - |f_model - f_test| / f_model) = 98 %.
    EXPECT_NEAR(j["pairs"][r]["agreement_pct"].get<double>(), 98.0, 1e-6);
  }
}

}  // namespace
}  // namespace ema::formats
