// `ema diagnose` on the diagnosis benchmark's first three cases (bench/diagnosis-benchmark, seed
// 2026: simulate → frf → fit → diagnose with the built ema) gives the DIAG.json numbers it gave
// before the run became one typed pipeline (issue 38; tests/data/golden/bench-case-000N.json).
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <nlohmann/json.hpp>

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
}

}  // namespace
}  // namespace ema
