// The project file of `ema run` (formats::ReadProjectFile, docs/project-file.md): bad input is an
// InputError naming the file, the line and the key or file at fault.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

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
}

}  // namespace
}  // namespace ema::formats
