// The project file of `ema run` (formats::ReadProjectFile, docs/project-file.md): bad input is an
// InputError naming the file, the line and the key or file at fault.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <utility>
#include <vector>

#include "ema/core/error.hpp"
#include "ema/formats/project_file.hpp"

namespace ema::formats {
namespace {

namespace fs = std::filesystem;

TEST(ProjectFile, BadInputNamesFileLineAndKey) {
  const fs::path dir = fs::path(EMA_TEST_TMP_DIR) / "project-bad";
  fs::create_directories(dir);
  auto write = [&](const std::string& name, const std::string& text) {
    std::ofstream(dir / name) << text;
    return dir / name;
  };
  write("model.toml", "[model]\nname = \"x\"\n");
  const fs::path unknown = write("unknown.toml", "[project]\nmodel = \"model.toml\"\ncolour = 3\n");
  try {
    ReadProjectFile(unknown);
    FAIL() << "unknown key accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("unknown.toml:3"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("colour"), std::string::npos) << e.what();
  }
  const fs::path missing = write("missing.toml", "[project]\nmodel = \"model.toml\"\n[[test]]\ntime = [\"nope.unv\"]\n");
  try {
    ReadProjectFile(missing);
    FAIL() << "missing data file accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("nope.unv"), std::string::npos) << e.what();
  }
  EXPECT_THROW(ReadProjectFile(write("notests.toml", "[project]\nmodel = \"model.toml\"\n")), InputError);
}

TEST(ProjectFile, ReadsTheGuidewaySample) {
  const Project p = ReadProjectFile(fs::path(EMA_SOURCE_DIR) / "samples" / "guideway" / "project.toml");
  ASSERT_EQ(p.tests.size(), 2u);
  EXPECT_EQ(p.tests[0].name, "stud-5um");
  EXPECT_EQ(p.tests[0].setup, "stud-5um");
  ASSERT_EQ(p.tests[0].time.size(), 1u);
  EXPECT_TRUE(p.tests[0].time[0].is_absolute());  // resolved against the project's folder
  EXPECT_EQ(p.estimator, "H1");
  ASSERT_TRUE(p.band_hz.has_value());
  EXPECT_EQ(p.band_hz->first, 100.0);
  EXPECT_EQ(p.band_hz->second, 450.0);
  EXPECT_EQ(p.select, "auto");
  EXPECT_EQ(p.lines.size(), 20u);
  EXPECT_FALSE(p.binary);
  EXPECT_EQ(p.tests[0].select, "");  // [fit] select applies
  EXPECT_FALSE(p.tests[0].pick);
}

// A test's own selection (a pick repeated without the browser) and pick = true (docs/pick.md):
// read as given; a selection `ema fit --select` would refuse is refused here, at its line.
TEST(ProjectFile, PerTestSelectAndPick) {
  const fs::path dir = fs::path(EMA_TEST_TMP_DIR) / "project-select";
  fs::create_directories(dir);
  std::ofstream(dir / "model.toml") << "[model]\nname = \"x\"\n";
  std::ofstream(dir / "frf.unv") << "";
  auto project = [&](const std::string& name, const std::string& test_keys) {
    std::ofstream(dir / name) << "[project]\nmodel = \"model.toml\"\n[[test]]\nfrf = \"frf.unv\"\n" << test_keys
                              << "[[test]]\nname = \"second\"\nfrf = \"frf.unv\"\n[fit]\nselect = \"auto\"\n";
    return dir / name;
  };
  const Project p = ReadProjectFile(project("good.toml", "select = \"196.4,267.25\"\npick = true\n"));
  ASSERT_EQ(p.tests.size(), 2u);
  EXPECT_EQ(p.tests[0].select, "196.4,267.25");
  EXPECT_TRUE(p.tests[0].pick);
  EXPECT_EQ(p.tests[1].select, "");
  EXPECT_FALSE(p.tests[1].pick);
  for (const auto& [keys, what] : std::vector<std::pair<std::string, std::string>>{
           {"select = \"196.4,,267\"\n", "select"},
           {"select = \"196.4 Hz\"\n", "select"},
           {"select = \"-3\"\n", "select"},
           {"select = 196.4\n", "select"},
           {"pick = \"yes\"\n", "pick"}}) {
    try {
      ReadProjectFile(project("bad.toml", keys));
      ADD_FAILURE() << keys << " accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("bad.toml:5"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("'" + what + "'"), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace ema::formats
