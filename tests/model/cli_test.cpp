// `ema model` and `ema simulate` end to end (runs the built executable).
#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <nlohmann/json.hpp>

#include "ema/formats/io.hpp"
#include "test_util.hpp"

namespace ema::model {
namespace {

namespace fs = std::filesystem;

const std::string kData = std::string(EMA_SOURCE_DIR) + "/tests/model/data/";

struct CliRun {
  int code = -1;
  std::string err;
};

CliRun Ema(const std::string& args, const fs::path& dir) {
  const fs::path err = dir / "stderr.txt";
  const std::string cmd = std::string(EMA_EXECUTABLE) + " " + args + " > " + (dir / "stdout.txt").string() + " 2> " + err.string();
  const int status = std::system(cmd.c_str());
  CliRun r;
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  std::ifstream in(err);
  r.err.assign(std::istreambuf_iterator<char>(in), {});
  return r;
}

TEST(Cli, ModelWritesModesAndJsonOfTheCarriage) {
  const fs::path dir = testing::TempDir("cli_model");
  fs::remove(dir / "modes.unv");
  const CliRun r = Ema("model " + kData + "carriage.toml --setup stud-5um -o " + (dir / "modes.unv").string() + " --json " +
                        (dir / "modes.json").string() + " --explain",
                    dir);
  ASSERT_EQ(r.code, 0) << r.err;
  std::ifstream in(dir / "modes.json");
  const nlohmann::json j = nlohmann::json::parse(in);
  ASSERT_EQ(j["modes"].size(), 5u);
  // Table 7.1 CR within 1.5 Hz (see thesis_carriage_test.cpp for the tolerance).
  EXPECT_NEAR(j["modes"][0]["frequency_hz"].get<double>(), 198.0, 1.5);
  EXPECT_EQ(j["modes"][0]["shape"].size(), 12u) << "4 test points x 3 directions";
  EXPECT_EQ(j["modes"][0]["shape"][2]["dir"], "+Z");
  const ModeSet read = formats::ReadModeSet(dir / "modes.unv");
  ASSERT_EQ(read.modes.size(), 5u);
  EXPECT_NEAR(read.modes[4].frequency_hz, j["modes"][4]["frequency_hz"].get<double>(), 1e-3);
  std::ifstream out(dir / "stdout.txt");
  const std::string text((std::istreambuf_iterator<char>(out)), {});
  EXPECT_NE(text.find("gap h = 12.7"), std::string::npos) << text;  // --explain: solved gap
}

TEST(Cli, ModelMaxModesKeepsTheLowestModes) {
  // The carriage has five elastic modes; --max-modes 2 keeps the two lowest, with the same
  // frequencies as the full solution (the same eigenproblem, fewer modes requested).
  const fs::path dir = testing::TempDir("cli_model_max_modes");
  const std::string base = "model " + kData + "carriage.toml --setup stud-5um ";
  ASSERT_EQ(Ema(base + "-o " + (dir / "all.unv").string() + " --json " + (dir / "all.json").string(), dir).code, 0);
  ASSERT_EQ(Ema(base + "-o " + (dir / "two.unv").string() + " --json " + (dir / "two.json").string() + " --max-modes 2", dir).code, 0);
  std::ifstream a(dir / "all.json"), t(dir / "two.json");
  const nlohmann::json all = nlohmann::json::parse(a), two = nlohmann::json::parse(t);
  ASSERT_EQ(all["modes"].size(), 5u);
  ASSERT_EQ(two["modes"].size(), 2u);
  for (int k = 0; k < 2; ++k)
    EXPECT_NEAR(two["modes"][k]["frequency_hz"].get<double>(), all["modes"][k]["frequency_hz"].get<double>(),
                1e-9 * all["modes"][k]["frequency_hz"].get<double>());
  EXPECT_EQ(Ema(base + "-o " + (dir / "x.unv").string() + " --max-modes -1", dir).code, 2);
}

TEST(Cli, ModelBadInputExitsOneAndWritesNothing) {
  const fs::path dir = testing::TempDir("cli_bad");
  std::ifstream src(kData + "carriage.toml");
  std::string text((std::istreambuf_iterator<char>(src)), {});
  const std::string from = "b = { body = \"ground\" }";
  text.replace(text.find(from), from.size(), "b = { body = \"frame\" }");
  fs::copy_file(kData + "film25.csv", dir / "film25.csv", fs::copy_options::overwrite_existing);
  const fs::path model = testing::WriteText(dir / "bad.toml", text);
  fs::remove(dir / "modes.unv");
  const CliRun r = Ema("model " + model.string() + " -o " + (dir / "modes.unv").string(), dir);
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("bad.toml:"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("unknown body 'frame'"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "modes.unv"));
  EXPECT_EQ(Ema("model " + kData + "carriage.toml", dir).code, 2) << "missing -o is a usage error";
  EXPECT_EQ(Ema("model " + kData + "carriage.toml --setup nope -o " + (dir / "m.unv").string(), dir).code, 1);
}

TEST(Cli, SimulateWritesOneForceAndThreeResponsesPerImpactAndSet) {
  const fs::path dir = testing::TempDir("cli_sim");
  const CliRun r = Ema("simulate " + kData + "carriage.toml --plan " + kData + "plan.toml -o " + (dir / "time.unv").string(), dir);
  ASSERT_EQ(r.code, 0) << r.err;
  const std::vector<TimeRecord> records = formats::ReadTimeRecords(dir / "time.unv");
  // 2 sets x 3 impacts x (1 force + 3 responses).
  ASSERT_EQ(records.size(), 24u);
  int forces = 0;
  for (const TimeRecord& t : records) {
    EXPECT_EQ(t.reference, (Dof{101, 3}));
    EXPECT_EQ(t.samples.size(), 4096u);
    forces += t.quantity == Quantity::kForce;
  }
  EXPECT_EQ(forces, 6);
}

TEST(Cli, SimulatePlanErrorsNameFileAndLine) {
  const fs::path dir = testing::TempDir("cli_sim_bad");
  const fs::path plan = testing::WriteText(dir / "plan.toml",
                                           "[plan]\nreferences = [\"101+Z\"]\n[[set]]\nsensors = [\"999+Z\"]\n");
  CliRun r = Ema("simulate " + kData + "carriage.toml --plan " + plan.string() + " -o " + (dir / "t.unv").string(), dir);
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("999"), std::string::npos) << r.err;
  testing::WriteText(plan, "[plan]\nreferences = [\"101+Q\"]\n[[set]]\nsensors = [\"101+Z\"]\n");
  r = Ema("simulate " + kData + "carriage.toml --plan " + plan.string() + " -o " + (dir / "t.unv").string(), dir);
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("plan.toml:2"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "t.unv"));
}

}  // namespace
}  // namespace ema::model
