// The edge of `ema run` (app/run_outputs.cpp): every output is a function of the typed result, and
// the terminal summary is one of them, not a source of the others — the guideway sample's run
// written twice, once with the summary reworded, gives the same files but summary.txt, byte for
// byte (the UFF files' time stamps aside).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>
#include <string>

#include "ema/formats/project_file.hpp"
#include "ema/pipeline/run.hpp"
#include "run_outputs.hpp"
#include "test_files.hpp"

namespace ema::app {
namespace {

namespace fs = std::filesystem;

// Every file of `dir` by its path relative to it; a UFF file's date lines ("27-Nov-26 11:12:44")
// are the writer's clock, masked.
std::map<std::string, std::string> Files(const fs::path& dir) {
  std::map<std::string, std::string> files;
  static const std::regex date("[0-9]{2}-[A-Z][a-z]{2}-[0-9]{2} [0-9]{2}:[0-9]{2}:[0-9]{2}");
  for (const auto& entry : fs::recursive_directory_iterator(dir)) {
    if (!entry.is_regular_file()) continue;
    std::string text = test::Slurp(entry.path());
    if (entry.path().extension() == ".unv") text = std::regex_replace(text, date, "DATE");
    files[fs::relative(entry.path(), dir).string()] = text;
  }
  return files;
}

TEST(RunOutputs, RewordingTheSummaryChangesNoOtherOutput) {
  const fs::path out = fs::path(EMA_TEST_TMP_DIR) / "run-outputs";
  fs::remove_all(out);
  const pipeline::RunResult run = pipeline::Run(pipeline::PlanFromProject(
      formats::ReadProjectFile(fs::path(EMA_SOURCE_DIR) / "samples/guideway/project.toml"), out));
  ASSERT_TRUE(run.Succeeded());
  const RunOutputOptions options{true, false, "2026-11-27 12:00 UTC"};
  auto write = [&](const RunSummaryWords& words) {
    fs::remove_all(out);
    for (const formats::ProjectTest& test : run.plan.project.tests) fs::create_directories(out / test.name);
    fs::create_directories(out / "logs");
    const RunOutputsWritten written = WriteRunOutputs(run, options, words);
    EXPECT_TRUE(written.problems.empty());
    return Files(out);
  };
  const std::map<std::string, std::string> plain = write(RunSummary);
  // Every sentence of the summary reworded.
  const std::map<std::string, std::string> reworded =
      write([](const pipeline::RunResult& r, const nlohmann::json& history, bool report, const std::vector<std::string>& problems) {
        std::string text = RunSummary(r, history, report, problems);
        for (const auto& [from, to] : std::map<std::string, std::string>{{"Adequate to the test's noise", "Fits the noise"},
                                                                            {"Diagnosis: the model misses", "Missing:"},
                                                                            {"Look-alikes", "Similar readings"}}) {
          const std::size_t at = text.find(from);
          EXPECT_NE(at, std::string::npos) << from;
          if (at != std::string::npos) text.replace(at, from.size(), to);
        }
        return "REWORDED\n" + text;
      });
  ASSERT_EQ(plain.size(), reworded.size());
  EXPECT_GE(plain.size(), 30u);  // every step's files, logs, diagnosis, model, history, report, summary
  for (const auto& [name, text] : plain) {
    ASSERT_TRUE(reworded.count(name)) << name;
    if (name == "summary.txt") {
      EXPECT_NE(text, reworded.at(name));
      EXPECT_EQ(reworded.at(name).rfind("REWORDED\n", 0), 0u);
    } else {
      EXPECT_TRUE(text == reworded.at(name)) << name << " changed with the summary's words";
    }
  }
  // The report carries no line of the summary: its first screen words the findings itself.
  std::istringstream lines(plain.at("summary.txt"));
  for (std::string line; std::getline(lines, line);) {
    if (line.find("Adequate to the test's noise") == std::string::npos) continue;
    EXPECT_EQ(plain.at("report.html").find(line.substr(line.find_first_not_of(' '))), std::string::npos) << line;
  }
}

}  // namespace
}  // namespace ema::app
