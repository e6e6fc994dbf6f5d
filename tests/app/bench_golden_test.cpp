// `ema diagnose` on the diagnosis benchmark's first three cases (bench/diagnosis-benchmark, seed
// 2026: simulate → frf → fit → diagnose with the built ema) gives the DIAG.json numbers it gave
// before the run became one typed pipeline (issue 38; tests/data/golden/bench-case-000N.json) —
// and so does `ema run` on the same cases, each test rehearsed from the case's plan on its truth
// (plan = …, truth = …: the simulate step inside the run, issue 40).
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "golden.hpp"
#include "test_files.hpp"

namespace ema {
namespace {

namespace fs = std::filesystem;

TEST(BenchGolden, FirstThreeCasesGiveTheirDiagnosisNumbers) {
  const fs::path work = fs::path(EMA_TEST_TMP_DIR) / "bench-golden";
  fs::remove_all(work);
  const std::string python = fs::exists("/usr/bin/python3") ? "/usr/bin/python3" : "python3";  // Debian's, with numpy
  const std::string command = python + " '" + EMA_SOURCE_DIR + "/bench/diagnosis-benchmark/bench.py' run --ema '" +
                              EMA_EXECUTABLE + "' --cases 0:3 --keep --work '" + work.string() + "' > '" +
                              work.string() + ".log' 2>&1";
  const int status = std::system(command.c_str());
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << test::Slurp(work.string() + ".log");
  for (const char* c : {"0000", "0001", "0002"}) {
    const nlohmann::json golden = nlohmann::json::parse(
        test::Slurp(fs::path(EMA_SOURCE_DIR) / "tests/data/golden" / (std::string("bench-case-") + c + ".json")));
    const nlohmann::json actual = nlohmann::json::parse(test::Slurp(work / "cases" / c / "diag.json"));
    int compared = 0;
    test::ExpectSameNumbers(golden["diagnosis"], actual, std::string("case ") + c, &compared);
    EXPECT_GT(compared, 300) << c;
  }

  // The same cases through `ema run`: per setup the case's plan rehearsed on its truth
  // (simulate.toml), the fit band bench.py gave `ema fit` (--band at 3 decimals).
  for (const char* c : {"0000", "0001", "0002"}) {
    const fs::path folder = work / "cases" / c;
    const nlohmann::json score = nlohmann::json::parse(test::Slurp(work / "scores" / (std::string("case-") + c + ".json")));
    std::vector<std::string> setups;  // plan-<setup>.toml; "test" when the model has no setups
    for (const auto& entry : fs::directory_iterator(folder)) {
      const std::string name = entry.path().filename().string();
      if (name.rfind("plan-", 0) == 0 && name.size() > 10 && name.substr(name.size() - 5) == ".toml")
        setups.push_back(name.substr(5, name.size() - 10));
    }
    std::sort(setups.begin(), setups.end());
    ASSERT_FALSE(setups.empty()) << c;
    char band[96];
    std::snprintf(band, sizeof band, "[%.3f, %.3f]", score["band_hz"][0].get<double>(), score["band_hz"][1].get<double>());
    const fs::path project = folder / "project.toml";
    {
      std::ofstream out(project);
      out << "[project]\nmodel = \"nominal.toml\"\n";
      for (const std::string& s : setups) {
        out << "[[test]]\nname = \"" << s << "\"\nplan = \"plan-" << s << ".toml\"\ntruth = \"simulate.toml\"\n";
        if (s != "test") out << "setup = \"" << s << "\"\n";
      }
      out << "[fit]\nband = " << band << "\n";
    }
    const fs::path run_dir = folder / "run";
    fs::create_directories(run_dir);
    ASSERT_EQ(test::RunEma("run '" + project.string() + "' -o '" + (run_dir / "out").string() + "' --no-report", run_dir), 0)
        << test::Slurp(run_dir / "stderr.txt") << test::Slurp(run_dir / "stdout.txt");
    const nlohmann::json golden = nlohmann::json::parse(
        test::Slurp(fs::path(EMA_SOURCE_DIR) / "tests/data/golden" / (std::string("bench-case-") + c + ".json")));
    const nlohmann::json actual = nlohmann::json::parse(test::Slurp(run_dir / "out" / "diagnosis.json"));
    int compared = 0;
    test::ExpectSameNumbers(golden["diagnosis"], actual, std::string("ema run, case ") + c, &compared);
    EXPECT_GT(compared, 300) << c;
  }
}

}  // namespace
}  // namespace ema
