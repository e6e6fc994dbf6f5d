// Bad input is first-class: malformed UFF files (generated here) fail with a message naming the
// file, the line, the dataset and the field; tolerated quirks read to the right numbers.
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>

#include "ema/core/error.hpp"
#include "ema/formats/io.hpp"
#include "ema/formats/uff.hpp"

namespace ema::formats::uff {
namespace {

namespace fs = std::filesystem;

fs::path Write(const std::string& name, const std::string& text) {
  fs::create_directories(EMA_TEST_TMP_DIR);
  const fs::path p = fs::path(EMA_TEST_TMP_DIR) / name;
  std::ofstream out(p, std::ios::binary);
  out << text;
  return p;
}

/// A valid ASCII 58 (real single, even, N values) as text, with hooks to break it.
std::string Header58(int n, const std::string& record7_type = "         2") {
  return "    -1\n    58\nNONE\nNONE\nNONE\nNONE\nNONE\n"
         "    1         0    0         3 NONE             101   1 NONE               1   3\n" +
         record7_type + std::string(10 - std::to_string(n).size(), ' ') + std::to_string(n) +
         "         1  0.00000E+00  1.00000E-03  0.00000E+00\n"
         "        17    0    0    0 Time                 s\n"
         "        12    1    0    0 Acceleration         m/s^2\n"
         "         0    0    0    0 NONE                 NONE\n"
         "         0    0    0    0 NONE                 NONE\n";
}

std::string ErrorOf(const fs::path& p, ReadOptions options = {}) {
  try {
    ReadFile(p, options);
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

// Line numbers below count the lines of Header58: delimiter 1, "58" 2, IDs 3-7, record 6 line 8,
// record 7 line 9, records 8-11 lines 10-13, values from line 14.

TEST(UffMalformed, EmptyFile) {
  const auto p = Write("empty.uff", "");
  EXPECT_EQ(ErrorOf(p), p.string() + ": empty file (no UFF dataset)");
}

TEST(UffMalformed, NotUff) {
  const auto p = Write("notuff.uff", "hello\nworld\n");
  EXPECT_EQ(ErrorOf(p), p.string() + ":1: not a UFF file: no '    -1' dataset delimiter found");
}

TEST(UffMalformed, TruncatedRecord) {
  // File cut after 4 of 6 values (no closing delimiter).
  const auto p = Write("trunc.uff", Header58(6) + "  1.00000E+00  2.00000E+00  3.00000E+00  4.00000E+00\n");
  EXPECT_EQ(ErrorOf(p), p.string() + ":14: dataset 58 record 12: truncated, got 4 of 6 values declared in record 7 (N = 6)");
  // Cut inside the header records.
  const auto q = Write("trunc_head.uff", "    -1\n    58\nNONE\nNONE\nNONE\n");
  EXPECT_EQ(ErrorOf(q), q.string() + ":5: dataset 58 record 4: truncated, the dataset ends before its 11 header records");
}

TEST(UffMalformed, WrongPointCount) {
  // Declares 4, holds 6 non-zero values.
  const auto p = Write("count.uff", Header58(4) + "  1.00000E+00  2.00000E+00  3.00000E+00  4.00000E+00  5.00000E+00  6.00000E+00\n    -1\n");
  EXPECT_EQ(ErrorOf(p), p.string() + ":14: dataset 58 record 12: more values than the N = 4 declared in record 7 field 2");
  // Declares 8, holds 6 before the delimiter.
  const auto q = Write("count2.uff", Header58(8) + "  1.00000E+00  2.00000E+00  3.00000E+00  4.00000E+00  5.00000E+00  6.00000E+00\n    -1\n");
  EXPECT_EQ(ErrorOf(q), q.string() + ":15: dataset 58 record 12: truncated, got 6 of 8 values declared in record 7 (N = 8)");
}

TEST(UffMalformed, BadNumber) {
  const auto p = Write("badnum.uff", Header58(3) + "  1.00000E+00  2.0.000E+00  3.00000E+00\n    -1\n");
  EXPECT_EQ(ErrorOf(p), p.string() + ":14: dataset 58 record 12: expected a real number, found '2.0.000E+00' (value 2)");
  // A bad integer in a fixed field names the record, field and columns.
  std::string h = Header58(3);
  h.replace(h.find("       101"), 10, "      1x1 ");
  const auto q = Write("badint.uff", h + "  1.00000E+00  2.00000E+00  3.00000E+00\n    -1\n");
  EXPECT_EQ(ErrorOf(q), q.string() + ":8: dataset 58 record 6 field 6 response node (columns 42-51): expected an integer, found '1x1'");
}

TEST(UffMalformed, GarbageAfterDelimiter) {
  const auto p = Write("garbage.uff", "    -1\nthis is not a dataset number\n    -1\n");
  EXPECT_EQ(ErrorOf(p), p.string() + ":2: expected a dataset number after the '-1' delimiter of line 1, found 'this is not a dataset number'");
}

TEST(UffMalformed, WrongCodes) {
  const auto p = Write("code.uff", Header58(1, "         3") + "  1.00000E+00\n    -1\n");
  EXPECT_EQ(ErrorOf(p), p.string() + ":9: dataset 58 record 7 field 1: ordinate data type must be 2, 4, 5 or 6, found 3");
  std::string h = Header58(1);
  h.replace(h.find("         1  0.00000E+00"), 10, "         7");
  const auto q = Write("spacing.uff", h + "  1.00000E+00\n    -1\n");
  EXPECT_EQ(ErrorOf(q), q.string() + ":9: dataset 58 record 7 field 3: abscissa spacing must be 0 or 1, found 7");
}

TEST(UffMalformed, NonFiniteValues) {
  const auto p = Write("nan.uff", Header58(2) + "  1.00000E+00          NaN\n    -1\n");
  EXPECT_EQ(ErrorOf(p), p.string() + ":14: dataset 58 record 12: non-finite value (value 2) not allowed");
  ReadOptions lenient;
  lenient.allow_non_finite = true;
  const auto ds = ReadFile(p, lenient);
  EXPECT_TRUE(std::isnan(std::get<Function58>(ds[0].body).y[1]));
}

TEST(UffMalformed, Binary58PayloadTooShort) {
  // Declares 4 doubles (32 bytes) but holds 12 bytes before the delimiter.
  std::string h = Header58(4, "         4");
  h.replace(h.find("    58\n"), 7, "    58b     1     2          11          32     0     0           0           0\n");
  const auto p = Write("short58b.uff", h + std::string(12, '\x01') + "    -1\n");
  EXPECT_EQ(ErrorOf(p), p.string() + ":14: dataset 58b payload: declared 32 bytes, expected 32 for N = 4, and no '-1' "
                                     "delimiter follows any plausible payload length");
}

TEST(UffMalformed, ErrorsFromTheFileLevelApi) {
  // ReadFrfSet on a file without FRFs says so, naming the file.
  const auto p = Write("nofrf.uff", Header58(1) + "  1.00000E+00\n    -1\n");
  try {
    ema::formats::ReadFrfSet(p);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), p.string() + ": no FRFs (dataset 58 with function type 4) in the file");
  }
  // The writer leaves nothing behind when it fails.
  const fs::path out = fs::path(EMA_TEST_TMP_DIR) / "never.uff";
  fs::remove(out);
  Function58 bad;
  bad.count = 2;
  bad.y = {1.0, std::nan("")};
  EXPECT_THROW(WriteFile(out, {Dataset{58, 0, 0, {}, bad}}), InputError);
  EXPECT_FALSE(fs::exists(out));
}

// ---- tolerated quirks -------------------------------------------------------------------

TEST(UffQuirks, FortranNumberForms) {
  double v = 0;
  struct Case {
    const char* text;
    double value;
  };
  const Case cases[] = {
      {"  1.23450E-02", 1.2345e-2}, {"  0.12345E-01", 0.012345},  {" 1.23450E-002", 1.2345e-2},
      {"1.2345000000000000D-02", 1.2345e-2}, {"1.2345000000000000E-2", 1.2345e-2}, {"  0.12345-100", 0.12345e-100},
      {"  1.23450+100", 1.2345e100},  {"1.234-05", 1.234e-5},    {"   0.01234500", 0.012345},
      {"            0", 0.0},         {"             ", 0.0},     {"+4.5", 4.5},
      {"-3.09944E-004", -3.09944e-4}, {"1.5d+3", 1500.0},        {"12345678901234567890123", 1.2345678901234568e22},
  };
  for (const auto& c : cases) {
    ASSERT_TRUE(ParseReal(c.text, &v)) << c.text;
    EXPECT_DOUBLE_EQ(v, c.value) << c.text;
  }
  EXPECT_TRUE(ParseReal("NaN", &v) && std::isnan(v));
  EXPECT_TRUE(ParseReal("-Inf", &v) && std::isinf(v) && v < 0);
  for (const char* bad : {"*************", "1.2.3", "E-05", "1.0E", "1,5", "abc", "1.0E-0x"}) EXPECT_FALSE(ParseReal(bad, &v)) << bad;
  std::int64_t i = 0;
  EXPECT_TRUE(ParseInteger("    66    ", &i));
  EXPECT_EQ(i, 66);
  EXPECT_TRUE(ParseInteger("9999999999", &i));  // I10 labels exceed 32 bits
  EXPECT_EQ(i, 9999999999);
  EXPECT_FALSE(ParseInteger("6 6", &i));
}

TEST(UffQuirks, DofInEntityName) {
  std::int64_t node = 0;
  int dir = 0;
  EXPECT_TRUE(DecodeEntityName(".1.Z-", &node, &dir));
  EXPECT_EQ(node, 1);
  EXPECT_EQ(dir, -3);
  EXPECT_TRUE(DecodeEntityName(".56.Z", &node, &dir));
  EXPECT_EQ(node, 56);
  EXPECT_EQ(dir, 3);
  EXPECT_TRUE(DecodeEntityName("1+Z", &node, &dir));
  EXPECT_EQ(dir, 3);
  EXPECT_TRUE(DecodeEntityName("101:-rx", &node, &dir));
  EXPECT_EQ(node, 101);
  EXPECT_EQ(dir, -4);
  for (const char* no : {"NONE", "Mic 01", "", ".1.Q", "Root", "12"}) EXPECT_FALSE(DecodeEntityName(no, &node, &dir)) << no;
  // dataset58_FRF.unv writes node 0, direction 0 and the names ".1.Z-" / ".56.Z" (sed -n 8p).
  const FrfSet s = ema::formats::ReadFrfSet(fs::path(EMA_REAL_DATA_DIR) / "uff/ufffiles-jl/dataset58_FRF.unv");
  ASSERT_EQ(s.OutputCount(), 1);
  EXPECT_EQ(s.outputs[0], (Dof{1, -3}));
  EXPECT_EQ(s.references[0], (Dof{56, 3}));
}

TEST(UffQuirks, WriterWidths) {
  EXPECT_EQ(FormatE(0.012345, 13, 5), "  1.23450E-02");
  EXPECT_EQ(FormatE(-1.0, 20, 12), " -1.000000000000E+00");
  EXPECT_EQ(FormatE(1.0, 25, 16, 'D'), "   1.0000000000000000D+00");
  EXPECT_EQ(FormatE(-1.2345e-100, 13, 5), "-1.23450E-100");
}

TEST(UffQuirks, CrlfJunkLinesLetterlessExponentsAndPaddedDelimiters) {
  // CRLF everywhere, delimiters padded to 80 columns, a comment line between datasets, a
  // letterless exponent, D exponent and 3-digit exponent values run together in their 13
  // columns, no newline at the end.
  std::string body = Header58(4) + "    1.234-005  2.50000D+00-3.00000E-001  4.00000E+00\n    -1" + std::string(74, ' ') + "\n";
  body += "comment written by some tool\n";
  body += "    -1\n    15\n         7         0         0         1 1.00000E+00 -2.00000E+00  3.00000E-01\n    -1";
  std::string crlf;
  for (char c : body) {
    if (c == '\n') crlf += '\r';
    crlf += c;
  }
  const auto p = Write("quirks.uff", crlf);
  Reader reader(p);
  Dataset d;
  ASSERT_TRUE(reader.Next(&d));
  const auto& f = std::get<Function58>(d.body);
  EXPECT_EQ(f.y, (std::vector<double>{1.234e-5, 2.5, -0.3, 4.0}));
  EXPECT_EQ(f.load_case, 3);
  EXPECT_EQ(f.axes[1].units, "m/s^2");
  ASSERT_TRUE(reader.Next(&d));
  EXPECT_EQ(d.line, 17);
  const auto& n = std::get<Nodes15>(d.body);
  ASSERT_EQ(n.nodes.size(), 1u);
  EXPECT_DOUBLE_EQ(n.nodes[0].xyz[2], 0.3);
  EXPECT_FALSE(reader.Next(&d));
  EXPECT_EQ(reader.FileNotes(), std::vector<std::string>{"line 16: text outside a dataset ignored"});
}

TEST(UffQuirks, BigEndianBinary58) {
  // Byte order 2 (big endian), real double even, N = 3: 1.5, -2.25, 1e-300.
  std::string h = Header58(3, "         4");
  h.replace(h.find("    58\n"), 7, "    58b     2     2          11          24     0     0           0           0\n");
  std::string payload;
  for (double v : {1.5, -2.25, 1e-300}) {
    std::uint64_t u;
    std::memcpy(&u, &v, 8);
    for (int b = 7; b >= 0; --b) payload.push_back(static_cast<char>((u >> (8 * b)) & 0xFF));
  }
  const auto p = Write("be58b.uff", h + payload + "    -1\n");
  const auto f = std::get<Function58>(ReadFile(p).at(0).body);
  EXPECT_TRUE(f.big_endian);
  EXPECT_EQ(f.y, (std::vector<double>{1.5, -2.25, 1e-300}));
}

TEST(UffQuirks, UnknownDatasetKeptVerbatim) {
  const std::string text = "    -1\n  2467\n         1\nsome group\n    1  2.5  what ever\n    -1\n";
  const auto p = Write("unknown.uff", text);
  const auto ds = ReadFile(p);
  ASSERT_EQ(ds.size(), 1u);
  EXPECT_EQ(ds[0].notes, std::vector<std::string>{"dataset 2467 is not decoded; kept verbatim"});
  const fs::path q = fs::path(EMA_TEST_TMP_DIR) / "unknown_rt.uff";
  WriteFile(q, ds);
  std::ifstream in(q, std::ios::binary);
  const std::string back((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(back, text);
}

TEST(UffQuirks, SixDofComplexModeShapeWrapsTwoLines) {
  // Corpus gap (spec §17): 55 with NDV 6 complex data, 12 numbers per node on two lines.
  Data55 a;
  a.analysis_type = 3;
  a.data_characteristic = 3;
  a.ndv = 6;
  a.integers = {1, 1};
  a.reals = {-1.0, 60.0, 1.0, 0.0, -1.0, 60.0};
  Data55::NodeValues nv;
  nv.node = 5;
  for (int k = 0; k < 12; ++k) nv.values.push_back(0.5 * (k + 1) * (k % 2 ? -1 : 1));
  a.nodes = {nv, nv};
  a.nodes[1].node = 6;
  const fs::path p = fs::path(EMA_TEST_TMP_DIR) / "six.uff";
  WriteFile(p, {Dataset{55, 0, 0, {}, a}});
  const auto b = std::get<Data55>(ReadFile(p).at(0).body);
  ASSERT_EQ(b.nodes.size(), 2u);
  EXPECT_EQ(b.nodes[1].node, 6);
  EXPECT_EQ(b.nodes[1].values, nv.values);
  EXPECT_EQ(b.integers, a.integers);
  EXPECT_EQ(b.reals, a.reals);
  // And as a mode set: 6 DOFs per node incl. rotations.
  const ModeSet m = ema::formats::ReadModeSet(p);
  EXPECT_EQ(m.dofs.size(), 12u);
  EXPECT_EQ(m.dofs[5], (Dof{5, 6}));
  EXPECT_EQ(m.modes[0].shape[5], std::complex<double>(5.5, -6.0));
}

}  // namespace
}  // namespace ema::formats::uff
