// `ema info`: summaries of real files (counts from the files themselves) and the CLI contract
// (exit 0 / 1 / 2, --help to stdout, --json).
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "ema/formats/info.hpp"
#include "ema/formats/io.hpp"

namespace ema::formats {
namespace {

namespace fs = std::filesystem;

fs::path Data(const std::string& rel) { return fs::path(EMA_REAL_DATA_DIR) / "uff" / rel; }

struct CliRun {
  int code;
  std::string out, err;
};

CliRun Ema(const std::string& args) {
  fs::create_directories(EMA_TEST_TMP_DIR);
  // Named by process: ctest runs the tests of this file in parallel processes.
  const std::string tag = std::to_string(getpid());
  const fs::path out = fs::path(EMA_TEST_TMP_DIR) / ("cli_out-" + tag + ".txt"),
                 err = fs::path(EMA_TEST_TMP_DIR) / ("cli_err-" + tag + ".txt");
  const std::string cmd = std::string("'") + EMA_EXECUTABLE + "' " + args + " >'" + out.string() + "' 2>'" + err.string() + "'";
  const int status = std::system(cmd.c_str());
  auto slurp = [](const fs::path& p) {
    std::ifstream in(p);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
  };
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, slurp(out), slurp(err)};
}

bool HaveEma() { return fs::exists(EMA_EXECUTABLE); }

TEST(FormatsInfo, SummaryOfBinaryTimeData) {
  // MPSTD...: 4 x 58b, function type 1, N = 222400, dx = 3.125E-04 (record 7, awk) -> 69.4997 s.
  const FileSummary s = SummarizeFile(Data("pyuff/MPSTD#Set001_2024_10_08_10_27_07.uff"));
  EXPECT_EQ(s.format, "uff");
  EXPECT_EQ(s.datasets, (std::map<int, int>{{58, 4}}));
  EXPECT_EQ(s.binary58, 4);
  EXPECT_EQ(s.records, 4);
  EXPECT_EQ(s.function_types, (std::map<int, int>{{1, 4}}));
  const auto& a = s.abscissa.at(1);
  EXPECT_EQ(a.points_min, 222400);
  EXPECT_EQ(a.points_max, 222400);
  EXPECT_DOUBLE_EQ(a.min, 0.0);
  EXPECT_NEAR(a.max, 222399 * 3.125e-4, 1e-9);
  EXPECT_EQ(a.units, std::set<std::string>{"s"});
  EXPECT_EQ(s.notes, std::vector<std::string>{"58b: line break after the payload (x4)"});
}

TEST(FormatsInfo, SummaryOfGeometryFile) {
  const FileSummary s = SummarizeFile(Data("pyuff/TestLab 161 164 18 15 82.uff"));
  EXPECT_EQ(s.datasets, (std::map<int, int>{{15, 1}, {18, 1}, {82, 3}, {151, 1}, {164, 1}}));
  EXPECT_EQ(s.geometry_nodes.size(), 36u);
  EXPECT_EQ(s.records, 0);
  EXPECT_EQ(s.units, std::vector<std::string>{"USER_DEFINED (code 9)"});
}

TEST(FormatsInfo, SummaryOfCsvTimeData) {
  const fs::path p = fs::path(EMA_TEST_TMP_DIR) / "info_impacts.csv";
  {
    std::ofstream out(p, std::ios::binary);
    out << "impact,time,force:3:+Z,acc:101:-X\n1,0,1,2\n1,0.5,3,4\n1,1,5,6\n2,0,1,2\n2,0.5,3,4\n";
  }
  const FileSummary s = SummarizeFile(p);
  EXPECT_EQ(s.format, "csv");
  EXPECT_EQ(s.records, 4);  // 2 channels x 2 impacts
  EXPECT_EQ(s.function_types, (std::map<int, int>{{1, 4}}));
  EXPECT_EQ(s.reference_dofs, (std::set<std::pair<std::int64_t, int>>{{3, 3}}));
  EXPECT_EQ(s.response_dofs, (std::set<std::pair<std::int64_t, int>>{{3, 3}, {101, -1}}));
  EXPECT_DOUBLE_EQ(s.abscissa.at(1).max, 1.0);
  EXPECT_EQ(s.abscissa.at(1).points_min, 2);
  EXPECT_EQ(s.abscissa.at(1).points_max, 3);
}

TEST(FormatsInfo, CliHelpAndExitCodes) {
  if (!HaveEma()) FAIL() << "ema executable not built: " << EMA_EXECUTABLE;
  CliRun r = Ema("info --help");
  EXPECT_EQ(r.code, 0);
  EXPECT_NE(r.out.find("ema info FILE"), std::string::npos) << r.out;
  r = Ema("info");
  EXPECT_EQ(r.code, 2) << r.err;
  r = Ema("info a.uff --no-such-option");
  EXPECT_EQ(r.code, 2) << r.err;
  r = Ema("info '" + (fs::path(EMA_TEST_TMP_DIR) / "missing.uff").string() + "'");
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("missing.uff: no such file"), std::string::npos) << r.err;
  const fs::path bad = fs::path(EMA_TEST_TMP_DIR) / "info_bad.uff";
  {
    std::ofstream out(bad, std::ios::binary);
    out << "    -1\n    58\nNONE\nNONE\n    -1\n";
  }
  r = Ema("info '" + bad.string() + "'");
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("info_bad.uff:5: dataset 58 record 3: truncated"), std::string::npos) << r.err;
}

TEST(FormatsInfo, CliSummaryAndJson) {
  if (!HaveEma()) FAIL() << "ema executable not built: " << EMA_EXECUTABLE;
  const fs::path json = fs::path(EMA_TEST_TMP_DIR) / "info.json";
  fs::remove(json);
  const CliRun r = Ema("info '" + Data("ufffiles-jl/dataset58_case8_binary.unv").string() + "' --json '" + json.string() + "'");
  ASSERT_EQ(r.code, 0) << r.err;
  // dataset58_case8_binary.unv: one 58b, FRF (type 4), N = 801, response 1 +X, reference 22 +X.
  EXPECT_NE(r.out.find("datasets: 58 x1 (1 of the 58 binary 58b)"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("function type 4 (frequency response function): 1, uneven abscissa"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("801 points"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("references: 1 DOFs at 1 nodes (22), directions +X"), std::string::npos) << r.out;
  std::ifstream in(json);
  std::stringstream s;
  s << in.rdbuf();
  EXPECT_NE(s.str().find("\"records\": 1"), std::string::npos) << s.str();
  EXPECT_NE(s.str().find("\"binary_58\": 1"), std::string::npos) << s.str();
}

// ---- Quirks of other tools' files (issue 28), each in a small file made here ----

fs::path WriteFile(const std::string& name, const std::string& bytes) {
  fs::create_directories(EMA_TEST_TMP_DIR);
  const fs::path p = fs::path(EMA_TEST_TMP_DIR) / (std::to_string(getpid()) + "-" + name);
  std::ofstream(p, std::ios::binary) << bytes;
  return p;
}

// One FRF (dataset 58, function type 4, 3 complex points); `units` is record 9's label, written as
// given (bytes), `dx` record 7's increment.
std::string Frf58(const std::string& units, const std::string& dx = "1.00000e+00") {
  return "    -1\n    58\nH1 101+X/101+X\nNONE\n25-Nov-26\nNONE\nNONE\n"
         "    4         1    0         0 NONE             101   1 NONE             101   1\n"
         "         6         3         1  1.00000e+01  " + dx + "  0.00000e+00\n"
         "        18    0    0    0 Frequency            Hz                  \n"
         "        12    0    0    0 Acceleration         " + units + "\n"
         "        13    0    0    0 Force                N                   \n"
         "         0    0    0    0 NONE                 NONE                \n"
         "  1.00000e+00  0.00000e+00  2.00000e+00  1.00000e+00  3.00000e+00 -1.00000e+00\n    -1\n";
}

// pyuff's non_ascii_header.uff and sample_dataset58_psd.uff: Latin-1 unit labels ("m/s²" as the
// byte 0xB2) made `ema info --json` exit 1 (invalid UTF-8 in JSON). Now kept and converted.
TEST(FormatsInfoQuirks, Latin1UnitLabelsAreConvertedToUtf8InJson) {
  if (!HaveEma()) FAIL() << "ema not built";
  const fs::path f = WriteFile("latin1.unv", Frf58("m/s\xB2"));
  const fs::path json = fs::path(EMA_TEST_TMP_DIR) / (std::to_string(getpid()) + "-latin1.json");
  const CliRun r = Ema("info '" + f.string() + "' --json '" + json.string() + "'");
  ASSERT_EQ(r.code, 0) << r.err;
  std::ifstream in(json);
  std::stringstream text;
  text << in.rdbuf();
  EXPECT_NE(text.str().find("m/s\xC2\xB2"), std::string::npos) << text.str();  // "m/s²" in UTF-8
  EXPECT_NE(r.out.find("m/s\xC2\xB2"), std::string::npos) << r.out;
}

// A record-7 error was reported on the dataset's first line; record 7 is its 9th line.
TEST(FormatsInfoQuirks, ARecordSevenErrorNamesItsOwnLine) {
  if (!HaveEma()) FAIL() << "ema not built";
  const fs::path f = WriteFile("record7.unv", Frf58("m/s2                ", "0.00000e+00"));
  const CliRun r = Ema("fit '" + f.string() + "' -o '" + f.string() + ".modes.unv'");
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find(f.string() + ":9: dataset 58 record 7 field 5"), std::string::npos) << r.err;
}

// FE modes as UFF 2414 (pyuff's "NX simulation output.uff": 176): `ema info` reported 0 modes
// while read_modes read them.
TEST(FormatsInfoQuirks, Dataset2414ModesAreCounted) {
  if (!HaveEma()) FAIL() << "ema not built";
  std::string text;
  for (int mode = 1; mode <= 2; ++mode) {
    text += "    -1\n  2414\n         " + std::to_string(mode) + "\nMode " + std::to_string(mode) +
            "\n         1\nNONE\nNONE\nNONE\nNONE\nNONE\n"
            "         1         2         2         8         2         3\n"
            "         0         0         " + std::to_string(mode) + "         0         0         1         0         0\n"
            "         0         0\n"
            "  0.00000E+00  " + (mode == 1 ? std::string("1.00000E+02") : std::string("2.50000E+02")) +
            "  0.00000E+00  1.00000E+00  0.00000E+00  0.00000E+00\n"
            "  0.00000E+00  0.00000E+00  0.00000E+00  0.00000E+00  0.00000E+00  0.00000E+00\n";
    for (int node = 1; node <= 3; ++node)
      text += "         " + std::to_string(node) + "\n  0.00000E+00  0.00000E+00  " + std::to_string(node * mode) +
              ".00000E+00\n";
    text += "    -1\n";
  }
  const fs::path f = WriteFile("fe2414.unv", text);
  const FileSummary s = SummarizeFile(f);
  EXPECT_EQ(s.modes, 2) << SummaryText(s);
  EXPECT_EQ(s.shape_nodes.size(), 3u);
}

// `ema info` failed on a folder that `ema fit` accepts (FRF tables).
TEST(FormatsInfoQuirks, AFolderOfFrfTablesIsSummarisedAsEmaFitReadsIt) {
  if (!HaveEma()) FAIL() << "ema not built";
  const fs::path dir = fs::path(EMA_TEST_TMP_DIR) / (std::to_string(getpid()) + "-frf-folder");
  fs::create_directories(dir);
  std::ofstream(dir / "frfs.csv") << "# frequency_hz: 0:2\nfile, response, reference\na.txt, 1+X, 1+X\nb.txt, 2+X, 1+X\n";
  std::ofstream(dir / "a.txt") << "(1+1j)\n(2+0j)\n(0.5-1j)\n";
  std::ofstream(dir / "b.txt") << "(1-1j)\n(2+0j)\n(0.5+1j)\n";
  const CliRun r = Ema("info '" + dir.string() + "'");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("folder of FRF tables"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("records: 2"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("0 .. 4 Hz"), std::string::npos) << r.out;
}

// Geometry with no units dataset (164) was silently taken as metres: now said.
TEST(FormatsInfoQuirks, GeometryWithoutUnitsDatasetIsStated) {
  const fs::path f = WriteFile("no164.unv",
                               "    -1\n    15\n         1         0         0        11  0.0000000E+00  0.0000000E+00  0.0000000E+00\n"
                               "         2         0         0        11  1.0000000E+03  0.0000000E+00  0.0000000E+00\n    -1\n");
  const FileSummary s = SummarizeFile(f);
  ASSERT_EQ(s.geometry_nodes.size(), 2u);
  bool said = false;
  for (const auto& n : s.notes) said = said || n.find("no units dataset (164)") != std::string::npos;
  EXPECT_TRUE(said) << SummaryText(s);
}

// Two real modes (100 and 200 Hz) at nodes 1 and 2 as UFF 55 records, without geometry.
std::string TwoModes55() {
  std::string text;
  for (int m = 1; m <= 2; ++m)
    text += "    -1\n    55\nmode\nNONE\nNONE\nNONE\nNONE\n"
            "         1         2         2         8         5         3\n"
            "         2         4         " + std::to_string(m) + "         " + std::to_string(m) + "\n"
            "  " + (m == 1 ? std::string("1.00000e+02") : std::string("2.00000e+02")) + "  0.00000e+00  0.00000e+00  1.00000e+00\n"
            "         1\n  1.00000e+00  0.00000e+00  0.00000e+00  0.00000e+00  0.00000e+00  0.00000e+00\n"
            "         2\n  0.50000e+00  0.00000e+00  0.00000e+00  0.00000e+00  0.00000e+00  0.00000e+00\n    -1\n";
  return text;
}

// The same gap in a mode file: the reader says so (ModeSet::geometry_units_note), `ema correlate`
// repeats it where it pairs nodes by distance, and ema's own mode files state SI.
TEST(FormatsInfoQuirks, ModeFileGeometryWithoutUnitsIsNotedAndEmaWritesUnits) {
  if (!HaveEma()) FAIL() << "ema not built";
  std::string text = "    -1\n    15\n         1         0         0        11  0.0000000E+00  0.0000000E+00  0.0000000E+00\n"
                     "         2         0         0        11  1.0000000E+03  0.0000000E+00  0.0000000E+00\n    -1\n";
  text += TwoModes55();
  const fs::path f = WriteFile("modes55_no164.unv", text);
  const ModeSet read = ReadModeSet(f);
  ASSERT_EQ(read.geometry.size(), 2u);
  EXPECT_DOUBLE_EQ(read.geometry[1].position.x(), 1000.0) << "taken as metres, as the note says";
  EXPECT_NE(read.geometry_units_note.find("no units dataset (164)"), std::string::npos);
  // Written back by ema: dataset 164 (SI) precedes the nodes, and the note is gone.
  const fs::path back = fs::path(EMA_TEST_TMP_DIR) / "modes55_with164.unv";
  WriteModeSet(back, read);
  const ModeSet again = ReadModeSet(back);
  EXPECT_TRUE(again.geometry_units_note.empty()) << again.geometry_units_note;
  EXPECT_DOUBLE_EQ(again.geometry[1].position.x(), 1000.0);
  // Correlating by distance repeats the note; by node id it has nothing to say.
  const CliRun by_distance = Ema("correlate --test '" + f.string() + "' --model '" + back.string() + "' --tolerance 0.01");
  EXPECT_EQ(by_distance.code, 0) << by_distance.err;
  EXPECT_NE(by_distance.err.find("no units dataset (164)"), std::string::npos) << by_distance.err;
  const CliRun by_id = Ema("correlate --test '" + f.string() + "' --model '" + back.string() + "'");
  EXPECT_EQ(by_id.code, 0) << by_id.err;
  EXPECT_EQ(by_id.err.find("no units dataset"), std::string::npos) << by_id.err;
}

// `ema quality --modes MODES.unv` alone failed with "the option '--input' is required".
TEST(FormatsInfoQuirks, QualityOfModesAloneNeedsNoFrfs) {
  if (!HaveEma()) FAIL() << "ema not built";
  const fs::path f = WriteFile("modes55.unv", TwoModes55());
  const CliRun r = Ema("quality --modes '" + f.string() + "'");
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("mode complexity: 2 checked"), std::string::npos) << r.out;
  EXPECT_EQ(Ema("quality").code, 2);
}

}  // namespace
}  // namespace ema::formats
