// `ema info`: summaries of real files (counts from the files themselves) and the CLI contract
// (exit 0 / 1 / 2, --help to stdout, --json).
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "ema/formats/info.hpp"

namespace ema::formats {
namespace {

namespace fs = std::filesystem;

fs::path Data(const std::string& rel) { return fs::path(EMA_SHARED_DATA_DIR) / "uff" / rel; }

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

}  // namespace
}  // namespace ema::formats
