// formats::StoredFrfSet / StoredModeSet (what a written UFF file holds, computed without the
// file) against the real round trip: WriteFrfSet/WriteModeSet then ReadFrfSet/ReadModeSet. They
// must agree bit for bit, since `ema run` hands these views on instead of reading its own files
// and promises the results of the subcommands run one after the other.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <random>

#include "ema/formats/io.hpp"
#include "formats/tmp_file.hpp"

namespace ema::formats {
namespace {

namespace fs = std::filesystem;

using test::TmpFile;

// Equal as bits, NaN equal to NaN (lines outside a measured range read back as NaN).
bool Same(double a, double b) { return (std::isnan(a) && std::isnan(b)) || a == b; }
bool Same(std::complex<double> a, std::complex<double> b) { return Same(a.real(), b.real()) && Same(a.imag(), b.imag()); }

// FRFs on a grid whose increment E13.5 cannot hold (0.15625 Hz · 1.0000013), with values that
// need all 17 digits, an unmeasured FRF and a coherence that starts later than its FRF.
FrfSet AwkwardFrfs() {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  FrfSet s;
  const int lines = 200;
  s.frequency_hz = Eigen::VectorXd::LinSpaced(lines, 0.0, 0.15625 * 1.0000013 * (lines - 1));
  s.outputs = {{101, 3}, {102, -2}, {103, 1}};
  s.references = {{1, 3}, {2, 3}};
  s.output_quantity = Quantity::kAcceleration;
  s.window_decay_rate = 3.14159265358979;
  s.roving_hammer = true;
  for (int r = 0; r < 2; ++r) {
    Eigen::MatrixXcd h(lines, 3);
    Eigen::MatrixXd c(lines, 3);
    for (int i = 0; i < lines; ++i)
      for (int o = 0; o < 3; ++o) h(i, o) = {u(rng) / 3.0, u(rng) * 1e-7 / 7.0}, c(i, o) = 0.5 + 0.4 * u(rng);
    h.col(2).setConstant({kNaN, kNaN});                            // 103+X not measured
    h.block(0, 1, 5, 1).setConstant({kNaN, kNaN});                 // 102-Y from line 5 on
    c.block(0, 0, 9, 1).setConstant(kNaN);
    s.h.push_back(h);
    s.coherence.push_back(c);
  }
  s.averages = Eigen::MatrixXi::Constant(2, 3, 5);
  return s;
}

void ExpectSameFrfs(const FrfSet& a, const FrfSet& b) {
  ASSERT_EQ(a.LineCount(), b.LineCount());
  for (int i = 0; i < a.LineCount(); ++i) ASSERT_TRUE(Same(a.frequency_hz[i], b.frequency_hz[i])) << "line " << i;
  EXPECT_EQ(a.outputs, b.outputs);
  EXPECT_EQ(a.references, b.references);
  ASSERT_EQ(a.h.size(), b.h.size());
  ASSERT_EQ(a.coherence.size(), b.coherence.size());
  for (std::size_t r = 0; r < a.h.size(); ++r)
    for (Eigen::Index i = 0; i < a.h[r].rows(); ++i)
      for (Eigen::Index o = 0; o < a.h[r].cols(); ++o) {
        ASSERT_TRUE(Same(a.h[r](i, o), b.h[r](i, o))) << "H ref " << r << " line " << i << " output " << o;
        ASSERT_TRUE(Same(a.coherence[r](i, o), b.coherence[r](i, o))) << "coherence " << r << " " << i << " " << o;
      }
  EXPECT_EQ(a.averages, b.averages);
  EXPECT_TRUE(Same(a.window_decay_rate, b.window_decay_rate));
  EXPECT_EQ(a.roving_hammer, b.roving_hammer);
  EXPECT_EQ(a.output_quantity, b.output_quantity);
  EXPECT_EQ(a.response_unit, b.response_unit);
  EXPECT_EQ(a.force_unit, b.force_unit);
}

TEST(StoredView, FrfSetIsWhatTheWrittenFileReadsBackAs) {
  const FrfSet frfs = AwkwardFrfs();
  for (const bool binary : {false, true}) {
    const fs::path file = TmpFile(binary ? "stored_view_b.unv" : "stored_view.unv");
    WriteOptions options;
    options.binary = binary;
    WriteFrfSet(file, frfs, options);
    ExpectSameFrfs(StoredFrfSet(frfs, options), ReadFrfSet(file));
  }
}

TEST(StoredView, StoredFrfSetDiffersFromTheValuesGiven) {
  // The reason the view exists: the file does not hold the values as given (the increment is cut
  // to six digits), so a stage fed the in-memory FRFs would not fit what `ema fit` fits.
  const FrfSet frfs = AwkwardFrfs();
  const FrfSet stored = StoredFrfSet(frfs);
  EXPECT_NE(stored.frequency_hz[100], frfs.frequency_hz[100]);
  EXPECT_NEAR(stored.frequency_hz[100], frfs.frequency_hz[100], 1e-5 * frfs.frequency_hz[100]);  // E13.5: 6 digits
}

TEST(StoredView, ModeSetIsWhatTheWrittenFileReadsBackAs) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  ModeSet set;
  set.source = "a fit";
  set.dofs = {{7, 3}, {7, 1}, {8, -2}, {9, 3}};
  set.geometry = {{7, {0.1234567891, 0.0, 0.3}}, {8, {1.0 / 3.0, 2.0, 0.0}}, {9, {0.0, 0.0, 0.0}}};
  for (int m = 0; m < 3; ++m) {
    Mode mode;
    mode.frequency_hz = 100.0 / 3.0 * (m + 1);
    mode.damping_ratio = 0.0123456789 * (m + 1);
    mode.pole = FrequencyAndDampingToPole(mode.frequency_hz, mode.damping_ratio);
    mode.mpc = 0.987654321;
    mode.frequency_std_hz = 0.01;  // UFF 55 has no place for it
    mode.shape = Eigen::VectorXcd(4);
    for (int d = 0; d < 4; ++d) mode.shape[d] = {u(rng) / 3.0, u(rng) / 7.0};
    mode.shape[3] = 0.0;  // a DOF that is zero in every mode is not a DOF of the file
    set.modes.push_back(mode);
  }
  const fs::path file = TmpFile("stored_view_modes.unv");
  WriteModeSet(file, set);
  const ModeSet read = ReadModeSet(file), stored = StoredModeSet(set, file);
  EXPECT_EQ(stored.source, read.source);
  EXPECT_EQ(stored.dofs, read.dofs);
  ASSERT_EQ(stored.geometry.size(), read.geometry.size());
  for (std::size_t n = 0; n < read.geometry.size(); ++n) {
    EXPECT_EQ(stored.geometry[n].id, read.geometry[n].id);
    for (int k = 0; k < 3; ++k) EXPECT_TRUE(Same(stored.geometry[n].position[k], read.geometry[n].position[k]));
  }
  ASSERT_EQ(stored.modes.size(), read.modes.size());
  for (std::size_t m = 0; m < read.modes.size(); ++m) {
    const Mode &a = stored.modes[m], &b = read.modes[m];
    EXPECT_TRUE(Same(a.frequency_hz, b.frequency_hz));
    EXPECT_TRUE(Same(a.damping_ratio, b.damping_ratio));
    EXPECT_TRUE(Same(a.pole, b.pole));
    EXPECT_TRUE(Same(a.mpc, b.mpc));
    EXPECT_TRUE(Same(a.frequency_std_hz, b.frequency_std_hz));
    ASSERT_EQ(a.shape.size(), b.shape.size());
    for (Eigen::Index d = 0; d < a.shape.size(); ++d) EXPECT_TRUE(Same(a.shape[d], b.shape[d])) << "mode " << m << " dof " << d;
  }
  EXPECT_NE(stored.modes[0].shape[0], set.modes[0].shape[0]);  // six digits, not the values given
}

}  // namespace
}  // namespace ema::formats
