// File-level API: time records, FRF sets and mode sets survive a UFF round trip; CSV and the
// complex column text format read the documented conventions.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <random>

#include "ema/core/error.hpp"
#include "ema/formats/io.hpp"
#include "ema/formats/uff.hpp"
#include "formats/tmp_file.hpp"

namespace ema::formats {
namespace {

namespace fs = std::filesystem;

using test::TmpFile;

void WriteText(const fs::path& p, const std::string& s) {
  std::ofstream out(p, std::ios::binary);
  out << s;
}

// Relative tolerance of E20.12 (13 significant digits) written values: half a unit in the
// 13th digit is 5e-13 relative; 1e-12 leaves room for the decimal->binary step.
constexpr double kE20Rel = 1e-12;

std::vector<TimeRecord> SyntheticHammerRecords() {
  // One impact at 3 +Z: a half-sine force pulse and two decaying responses with noise.
  std::mt19937 rng(42);
  std::normal_distribution<double> noise(0.0, 1e-3);
  const double dt = 1.0 / 2048.0;
  std::vector<TimeRecord> out;
  for (int impact = 1; impact <= 2; ++impact) {
    TimeRecord f;
    f.channel = {3, 3};
    f.reference = {3, 3};
    f.impact = impact;
    f.quantity = Quantity::kForce;
    f.sample_interval_s = dt;
    f.unit = "N";
    for (int i = 0; i < 1000; ++i) f.samples.push_back((i < 10 ? 100.0 * std::sin(kTwoPi * i / 20.0) : 0.0) + noise(rng));
    out.push_back(f);
    for (int node : {101, 102}) {
      TimeRecord a = f;
      a.channel = {node, node == 101 ? 1 : -2};
      a.quantity = Quantity::kAcceleration;
      a.unit = "m/s^2";
      a.samples.clear();
      for (int i = 0; i < 1000; ++i)
        a.samples.push_back(std::exp(-20.0 * i * dt) * std::sin(kTwoPi * 50.0 * i * dt) * node + noise(rng));
      out.push_back(a);
    }
  }
  return out;
}

TEST(FormatsIo, TimeRecordsRoundTripAsciiAndBinary) {
  const auto records = SyntheticHammerRecords();
  for (bool binary : {false, true}) {
    const fs::path p = TmpFile(binary ? "time_b.uff" : "time_a.uff");
    WriteTimeRecords(p, records, {binary});
    const auto back = ReadTimeRecords(p);
    ASSERT_EQ(back.size(), records.size());
    for (size_t i = 0; i < records.size(); ++i) {
      EXPECT_EQ(back[i].channel, records[i].channel);
      EXPECT_EQ(back[i].reference, records[i].reference);
      EXPECT_EQ(back[i].impact, records[i].impact);
      EXPECT_EQ(back[i].quantity, records[i].quantity);
      EXPECT_EQ(back[i].unit, records[i].unit);
      // dt = 1/2048 is printed as 4.88281E-04 (E13.5) and snapped back to 1/2048 exactly.
      EXPECT_DOUBLE_EQ(back[i].sample_interval_s, 1.0 / 2048.0);
      ASSERT_EQ(back[i].samples.size(), records[i].samples.size());
      for (size_t k = 0; k < records[i].samples.size(); ++k) {
        // Binary 58b (double) is exact; ASCII E20.12 keeps 13 significant digits.
        const double tol = binary ? 0.0 : kE20Rel * std::abs(records[i].samples[k]);
        EXPECT_NEAR(back[i].samples[k], records[i].samples[k], tol);
      }
    }
  }
}

TEST(FormatsIo, TimeRecordsImpactGroupingWithoutLoadCases) {
  // A file that numbers nothing: load case 0 and version 0 everywhere, no reference DOF.
  auto records = SyntheticHammerRecords();
  for (auto& r : records) {
    r.impact = 0;
    r.reference = {};
  }
  const fs::path p = TmpFile("time_nolc.uff");
  WriteTimeRecords(p, records);
  const auto back = ReadTimeRecords(p);
  ASSERT_EQ(back.size(), 6u);
  // Rule: a new impact at each force record; references taken from the force channel.
  const int expected[] = {1, 1, 1, 2, 2, 2};
  for (size_t i = 0; i < back.size(); ++i) {
    EXPECT_EQ(back[i].impact, expected[i]) << i;
    EXPECT_EQ(back[i].reference, (Dof{3, 3})) << i;
  }
}

FrfSet SyntheticFrfSet() {
  // Two references, three outputs, one SDOF-like mode with noise; line 0 not measured (NaN).
  FrfSet s;
  const int n = 201;
  s.frequency_hz = Eigen::VectorXd::LinSpaced(n, 0.0, 200.0);
  s.outputs = {{1, 1}, {2, 2}, {3, -3}};
  s.references = {{1, 1}, {7, 3}};
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 1e-4);
  const std::complex<double> pole = FrequencyAndDampingToPole(80.0, 0.02);
  for (int r = 0; r < 2; ++r) {
    Eigen::MatrixXcd h(n, 3);
    Eigen::MatrixXd c(n, 3);
    for (int o = 0; o < 3; ++o)
      for (int i = 0; i < n; ++i) {
        const std::complex<double> jw(0.0, kTwoPi * s.frequency_hz[i]);
        h(i, o) = -(jw * jw) * (double(o + 1 + r) / (jw - pole) + std::conj(double(o + 1 + r) / (jw - std::conj(pole))));
        h(i, o) += std::complex<double>(noise(rng), noise(rng));
        c(i, o) = 0.9 + 0.05 * std::sin(i * 0.1 + o);
      }
    h.row(0).setConstant(std::complex<double>(kNaN, kNaN));
    c.row(0).setConstant(kNaN);
    s.h.push_back(h);
    s.coherence.push_back(c);
  }
  s.averages = Eigen::MatrixXi::Constant(2, 3, 5);
  s.window_decay_rate = 12.5;
  return s;
}

TEST(FormatsIo, FrfSetRoundTrip) {
  const FrfSet s = SyntheticFrfSet();
  for (bool binary : {false, true}) {
    const fs::path p = TmpFile(binary ? "frf_b.uff" : "frf_a.uff");
    WriteFrfSet(p, s, {binary});
    const FrfSet b = ReadFrfSet(p);
    ASSERT_EQ(b.LineCount(), s.LineCount());
    EXPECT_EQ(b.outputs, s.outputs);
    EXPECT_EQ(b.references, s.references);
    EXPECT_EQ(b.output_quantity, Quantity::kAcceleration);
    EXPECT_EQ(b.averages, s.averages);
    EXPECT_DOUBLE_EQ(b.window_decay_rate, 12.5);
    ASSERT_EQ(b.coherence.size(), 2u);
    for (int i = 0; i < s.LineCount(); ++i) EXPECT_DOUBLE_EQ(b.frequency_hz[i], s.frequency_hz[i]);
    for (int r = 0; r < 2; ++r)
      for (int o = 0; o < 3; ++o) {
        EXPECT_TRUE(std::isnan(b.h[r](0, o).real()));  // the unmeasured line stays unmeasured
        for (int i = 1; i < s.LineCount(); ++i) {
          const double tol = binary ? 0.0 : kE20Rel * std::abs(s.h[r](i, o)) * 2;
          EXPECT_NEAR(b.h[r](i, o).real(), s.h[r](i, o).real(), tol);
          EXPECT_NEAR(b.h[r](i, o).imag(), s.h[r](i, o).imag(), tol);
          EXPECT_NEAR(b.coherence[r](i, o), s.coherence[r](i, o), binary ? 0.0 : 1e-12);
        }
      }
  }
  // The written file declares FRF type 4 and coherence type 6 with the right data codes.
  const auto ds = uff::ReadFile(TmpFile("frf_a.uff"));
  ASSERT_EQ(ds.size(), 12u);
  const auto& f = std::get<uff::Function58>(ds[0].body);
  EXPECT_EQ(f.function_type, 4);
  EXPECT_EQ(f.ordinate_type, 6);
  EXPECT_EQ(f.axes[0].specific_data_type, 18);
  EXPECT_EQ(f.axes[1].specific_data_type, 12);
  EXPECT_EQ(f.axes[2].specific_data_type, 13);
  EXPECT_EQ(f.axes[1].length_exponent, 1);
  EXPECT_EQ(f.axes[2].force_exponent, 1);
  const auto& c = std::get<uff::Function58>(ds[1].body);
  EXPECT_EQ(c.function_type, 6);
  EXPECT_EQ(c.ordinate_type, 4);
}

TEST(FormatsIo, FrfSetWithInteriorNaNIsRejected) {
  FrfSet s = SyntheticFrfSet();
  s.h[0](50, 1) = {kNaN, 0.0};
  try {
    WriteFrfSet(TmpFile("frf_nan.uff"), s);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("non-finite value at line 50"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(TmpFile("frf_nan.uff")));
}

ModeSet SyntheticModes() {
  ModeSet m;
  m.source = "synthetic";
  for (int n = 1; n <= 4; ++n) {
    m.geometry.push_back({n, Eigen::Vector3d(0.1 * n, -0.25 * n, 0.5)});
    m.dofs.push_back({n, 1});
    m.dofs.push_back({n, 3});
  }
  for (int k = 0; k < 3; ++k) {
    Mode mode;
    mode.frequency_hz = 52.123456789 * (k + 1);
    mode.damping_ratio = 0.01 + 0.003 * k;
    mode.pole = FrequencyAndDampingToPole(mode.frequency_hz, mode.damping_ratio);
    mode.shape.resize(8);
    for (int i = 0; i < 8; ++i) mode.shape[i] = {std::cos(0.7 * i * (k + 1)), 0.1 * std::sin(0.3 * i + k)};
    mode.mpc = 0.987654;
    m.modes.push_back(mode);
  }
  return m;
}

TEST(FormatsIo, ModeSetRoundTrip) {
  const ModeSet m = SyntheticModes();
  const fs::path p = TmpFile("modes.unv");
  WriteModeSet(p, m);
  const ModeSet b = ReadModeSet(p);
  EXPECT_EQ(b.dofs, m.dofs);
  ASSERT_EQ(b.modes.size(), 3u);
  ASSERT_EQ(b.geometry.size(), 4u);
  for (size_t i = 0; i < 4; ++i) {
    EXPECT_EQ(b.geometry[i].id, m.geometry[i].id);
    // Dataset 15 coordinates are E13.5: 6 significant digits.
    EXPECT_NEAR((b.geometry[i].position - m.geometry[i].position).norm(), 0.0, 5e-6);
  }
  for (size_t k = 0; k < 3; ++k) {
    // f and zeta travel in ID line 5 with 12 significant digits.
    EXPECT_NEAR(b.modes[k].frequency_hz, m.modes[k].frequency_hz, 1e-9 * m.modes[k].frequency_hz);
    EXPECT_NEAR(b.modes[k].damping_ratio, m.modes[k].damping_ratio, 1e-11);
    EXPECT_NEAR(b.modes[k].mpc, 0.987654, 1e-6);
    for (int i = 0; i < 8; ++i) {
      // Shape values are E13.5 (6 significant digits): |error| <= 5e-6 * |value| (+ rounding).
      EXPECT_NEAR(b.modes[k].shape[i].real(), m.modes[k].shape[i].real(), 6e-6 * std::abs(m.modes[k].shape[i]));
      EXPECT_NEAR(b.modes[k].shape[i].imag(), m.modes[k].shape[i].imag(), 6e-6 * std::abs(m.modes[k].shape[i]));
    }
  }
}

void ExpectMeasPointBeam(const FrfSet& s) {
  ASSERT_EQ(s.LineCount(), 1001);
  EXPECT_EQ(s.ReferenceCount(), 3);
  EXPECT_EQ(s.OutputCount(), 1);
  EXPECT_EQ(s.outputs[0], (Dof{1, 1}));
  EXPECT_EQ(s.references[2], (Dof{3, 1}));
  EXPECT_DOUBLE_EQ(s.frequency_hz[1000], 1000.0);
  EXPECT_EQ(s.output_quantity, Quantity::kAcceleration);
  // First lines of meas_point_1.txt and meas_point_3.txt, read by hand.
  EXPECT_DOUBLE_EQ(s.h[0](0, 0).real(), -0.0774752256830106);
  EXPECT_DOUBLE_EQ(s.h[0](0, 0).imag(), 2.6838208936737454e-08);
  EXPECT_DOUBLE_EQ(s.h[0](1, 0).real(), -0.17515115491765987);
  EXPECT_DOUBLE_EQ(s.h[0](1, 0).imag(), -0.12042372070051006);
  EXPECT_DOUBLE_EQ(s.h[2](1, 0).real(), 0.010496299469543217);
  EXPECT_DOUBLE_EQ(s.h[2](1, 0).imag(), -0.0970558419720156);
}

TEST(FormatsIo, MeasPointFrfsAsPublishedWithoutIndex) { ExpectMeasPointBeam(ReadFrfSet(fs::path(EMA_REAL_DATA_DIR) / "frf-meas-point")); }

TEST(FormatsIo, MeasPointSampleThroughItsIndex) {
  ExpectMeasPointBeam(ReadFrfSet(fs::path(EMA_SOURCE_DIR) / "samples" / "meas-point"));
}

TEST(FormatsIo, FrfTableAnyDofsReImPairsAndMissingFrfs) {
  // Two responses, two references, one FRF (101-Z from 7+Y) not measured; whitespace separated,
  // one FRF as an re:/im: column pair. Every value below is read back exactly.
  const fs::path p = TmpFile("table.txt");
  WriteText(p,
            "# quantity: mobility\n"
            "frequency_hz  3:+Z/7+Y   re:101-Z/3+Z  im:101-Z/3+Z  3+Z/3+Z\n"
            "10.0  (1+2j)  0.5  -0.25  7\n"
            "10.5  (3-4e-1j)  1.5  2.5  nan\n"
            "11.0  -1-1j  0  1  (0+0j)\n");
  const FrfSet s = ReadFrfSet(p);
  ASSERT_EQ(s.LineCount(), 3);
  EXPECT_DOUBLE_EQ(s.frequency_hz[2], 11.0);
  EXPECT_EQ(s.output_quantity, Quantity::kVelocity);
  EXPECT_EQ(s.response_unit, "m/s");
  ASSERT_EQ(s.outputs, (std::vector<Dof>{{3, 3}, {101, -3}}));
  ASSERT_EQ(s.references, (std::vector<Dof>{{7, 2}, {3, 3}}));
  EXPECT_EQ(s.h[0](1, 0), std::complex<double>(3.0, -0.4));
  EXPECT_TRUE(std::isnan(s.h[0](0, 1).real()));  // 101-Z/7+Y: not in the table
  EXPECT_EQ(s.h[1](1, 1), std::complex<double>(1.5, 2.5));
  EXPECT_EQ(s.h[1](2, 1), std::complex<double>(0.0, 1.0));
  EXPECT_EQ(s.h[1](0, 0), std::complex<double>(7.0, 0.0));
  EXPECT_TRUE(std::isnan(s.h[1](1, 0).real()));  // a missing line
}

TEST(FormatsIo, FrfTableErrorsNameFileAndLine) {
  const fs::path p = TmpFile("bad_table.csv");
  auto expect_error = [&](const std::string& text, const std::string& fragment) {
    WriteText(p, text);
    try {
      ReadFrfSet(p);
      ADD_FAILURE() << "no error for: " << text;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
    }
  };
  expect_error("frequency_hz,1+X/2+X\n0,1\n1,1\n2.5,1\n", "bad_table.csv:4: frequencies must be evenly spaced");
  expect_error("frequency_hz,1+X\n0,1\n", "bad_table.csv:1: column '1+X': expected RESPONSE/REFERENCE");
  expect_error("time,1+X/2+X\n0,1\n", "bad_table.csv:1: expected a header such as");
  expect_error("frequency_hz,1+X/2+X,1+X/2+X\n0,1,1\n1,1,1\n", "FRF 1+X/2+X given twice");
  expect_error("frequency_hz,re:1+X/2+X\n0,1\n1,1\n", "im: column missing");
  expect_error("frequency_hz,1+X/2+X\n0,1\n1,(1+x)\n", "bad_table.csv:3: column 2: expected a complex number");
  expect_error("frequency_hz,1+X/2+X\n0,1,3\n", "bad_table.csv:2: expected 2 cells like the header, found 3");
  expect_error("# quantity: force\nfrequency_hz,1+X/2+X\n0,1\n", "bad_table.csv:1: quantity: expected acceleration");
  // A folder of column files without its index says what the index must hold.
  const fs::path dir = fs::path(EMA_TEST_TMP_DIR) / "frf_columns_without_index";
  fs::remove_all(dir);
  fs::create_directories(dir);
  WriteText(dir / "a.txt", "(1+1j)\n");
  try {
    ReadFrfSet(dir);
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("needs an index 'frfs.csv'"), std::string::npos) << e.what();
  }
  // An index whose column files differ in length names the offending file.
  WriteText(dir / "b.txt", "(1+1j)\n(2+2j)\n");
  WriteText(dir / "frfs.csv", "# frequency_hz: 0:1\nfile,response,reference\na.txt,1+X,1+X\nb.txt,1+X,2+X\n");
  try {
    ReadFrfSet(dir);
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("b.txt: expected 1 values"), std::string::npos) << e.what();
  }
}

TEST(FormatsIo, ComplexColumnTextForms) {
  const fs::path p = TmpFile("cols.txt");
  WriteText(p, "(nan+nanj)\n(1.5-2e-03j)\n# comment\n\n-3.25+4j\nnan\n7\n(-0-1j)\n");
  const Eigen::VectorXcd v = ReadComplexColumnText(p);
  ASSERT_EQ(v.size(), 6);
  EXPECT_TRUE(std::isnan(v[0].real()) && std::isnan(v[0].imag()));
  EXPECT_EQ(v[1], std::complex<double>(1.5, -2e-3));
  EXPECT_EQ(v[2], std::complex<double>(-3.25, 4.0));
  EXPECT_TRUE(std::isnan(v[3].real()));
  EXPECT_EQ(v[4], std::complex<double>(7.0, 0.0));
  EXPECT_EQ(v[5], std::complex<double>(0.0, -1.0));
  WriteText(p, "(1+2j)\n(1+x2j)\n");
  try {
    ReadComplexColumnText(p);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("cols.txt:2"), std::string::npos) << e.what();
  }
}

TEST(FormatsIo, CsvOneFilePerImpact) {
  const fs::path p = TmpFile("point3_impact4.csv");
  WriteText(p, "# hammer test\ntime,force:3:+Z[N],acc:101:+X[g]\n0,0.5,0.1\n0.001,1.5,-0.2\n0.002,0.25,0.3\n");
  const auto r = ReadTimeRecords(p);
  ASSERT_EQ(r.size(), 2u);
  EXPECT_EQ(r[0].quantity, Quantity::kForce);
  EXPECT_EQ(r[0].channel, (Dof{3, 3}));
  EXPECT_EQ(r[1].channel, (Dof{101, 1}));
  EXPECT_EQ(r[1].reference, (Dof{3, 3}));
  EXPECT_EQ(r[1].impact, 4);  // from the file name
  EXPECT_EQ(r[1].unit, "g");
  EXPECT_DOUBLE_EQ(r[0].sample_interval_s, 0.001);
  EXPECT_EQ(r[1].samples, (std::vector<double>{0.1, -0.2, 0.3}));
}

TEST(FormatsIo, CsvImpactColumnRoundTrip) {
  const auto records = SyntheticHammerRecords();
  const fs::path p = TmpFile("hammer.csv");
  WriteCsvTimeRecords(p, records);
  const auto back = ReadTimeRecords(p);
  ASSERT_EQ(back.size(), records.size());
  for (size_t i = 0; i < records.size(); ++i) {
    EXPECT_EQ(back[i].channel, records[i].channel);
    EXPECT_EQ(back[i].reference, records[i].reference);
    EXPECT_EQ(back[i].impact, records[i].impact);
    EXPECT_EQ(back[i].samples, records[i].samples);  // shortest round-trip printing is exact
    EXPECT_DOUBLE_EQ(back[i].sample_interval_s, records[i].sample_interval_s);
  }
}

TEST(FormatsIo, CsvErrorsNameFileLineAndColumn) {
  const fs::path p = TmpFile("bad.csv");
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"time,force:1:+Z,acc:101:+Q\n0,1,2\n", "bad.csv:1: column 'acc:101:+Q': direction"},
      {"time,force:1:+Z,acc:101:+X\n0,1,2\n0.1,abc,3\n", "bad.csv:3: column 'force:1:+Z': expected a finite number, found 'abc'"},
      {"time,force:1:+Z\n0,1\n0.1,2,3\n", "bad.csv:3: expected 2 fields"},
      {"force:1:+Z,acc:2:+X\n1,2\n", "bad.csv:1: no 'time' column"},
      {"time,force:1:+Z\n0,1\n0.1,1\n0.5,1\n", "not uniformly sampled"},
      {"time,weight:1:+Z\n0,1\n", "unknown role 'weight'"},
  };
  for (const auto& [text, expected] : cases) {
    WriteText(p, text);
    try {
      ReadTimeRecords(p);
      ADD_FAILURE() << "no error for: " << text;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace ema::formats

namespace ema::formats {
namespace {

// A Test.Lab-style file: node 7 measured in its own displacement coordinate system SYS1 of
// spec §7 (x̂ = −X, ŷ = +Y, ẑ = −Z). The reader must hand back shapes in the global frame:
// local (1, 2, 3) becomes global (−1, 2, −3) exactly (a rotation by ±1 entries, no rounding).
TEST(IoModeSet, DisplacementCoordinateSystemsAreRotatedToGlobal) {
  uff::CoordinateSystems18 cs;
  uff::CoordinateSystem18 sys1;
  sys1.number = 1;
  sys1.name = "SYS1";
  sys1.points = {-2.4, -0.95, 0.0, -3.4, -0.95, 0.0, -3.4, -0.95, -1.0};
  cs.systems.push_back(sys1);
  uff::Nodes15 nodes;
  nodes.nodes.push_back({7, 0, 1, 8, {0.1, 0.2, 0.3}});
  nodes.nodes.push_back({8, 0, 0, 8, {0.4, 0.5, 0.6}});
  uff::Data55 mode;
  mode.reals = {-1.0, 2 * 3.14159265358979 * 50.0, 1.0, 0.0};  // complex pole, modal A
  mode.nodes.push_back({7, {1.0, 0.0, 2.0, 0.0, 3.0, 0.5}});
  mode.nodes.push_back({8, {1.0, 0.0, 2.0, 0.0, 3.0, 0.5}});
  const fs::path p = fs::path(EMA_TEST_TMP_DIR) / "io_displacement_cs.uff";
  fs::create_directories(EMA_TEST_TMP_DIR);
  uff::WriteFile(p, {uff::Dataset{18, 0, 0, {}, cs}, uff::Dataset{15, 0, 0, {}, nodes}, uff::Dataset{55, 0, 0, {}, mode}});
  const ModeSet set = ReadModeSet(p);
  ASSERT_EQ(set.modes.size(), 1u);
  auto value = [&](int node, int dir) {
    for (size_t i = 0; i < set.dofs.size(); ++i)
      if (set.dofs[i] == Dof{node, dir}) return set.modes[0].shape[static_cast<Eigen::Index>(i)];
    ADD_FAILURE() << "missing DOF " << node << " " << dir;
    return std::complex<double>();
  };
  EXPECT_NEAR(std::abs(value(7, 1) - std::complex<double>(-1.0, 0.0)), 0.0, 1e-12);
  EXPECT_NEAR(std::abs(value(7, 2) - std::complex<double>(2.0, 0.0)), 0.0, 1e-12);
  EXPECT_NEAR(std::abs(value(7, 3) - std::complex<double>(-3.0, -0.5)), 0.0, 1e-12);
  // Node 8 is in the global system: untouched.
  EXPECT_NEAR(std::abs(value(8, 1) - std::complex<double>(1.0, 0.0)), 0.0, 1e-12);
  EXPECT_NEAR(std::abs(value(8, 3) - std::complex<double>(3.0, 0.5)), 0.0, 1e-12);

  // A node that names a system the file does not define is an error that says which.
  nodes.nodes[1].displacement_cs = 5;
  uff::WriteFile(p, {uff::Dataset{18, 0, 0, {}, cs}, uff::Dataset{15, 0, 0, {}, nodes}, uff::Dataset{55, 0, 0, {}, mode}});
  try {
    ReadModeSet(p);
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("displacement coordinate system 5"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace ema::formats
