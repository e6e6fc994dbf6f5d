// Test modes as MODES.json (model-format.md "Test modes measured by other tools", added turn 3):
// `ema fit --json`'s layout read back, real shapes, only the measured DOFs, measured σ; bad input.
#include <gtest/gtest.h>

#include <fstream>

#include "ema/core/error.hpp"
#include "ema/formats/io.hpp"
#include "ema/formats/json_codecs.hpp"
#include "tmp_file.hpp"

namespace ema::formats {
namespace {

std::filesystem::path Write(const std::string& name, const std::string& text) {
  const auto path = test::TmpFile(name);
  std::ofstream(path) << text;
  return path;
}

std::string ErrorOf(const std::string& text) {
  try {
    ReadModeSet(Write("bad-modes.json", text));
  } catch (const InputError& e) {
    return e.what();
  }
  return "no error";
}

// What `ema fit --json` writes (ModeSetJson) reads back as the same modes, σ included.
TEST(ModesJson, FitJsonLayoutRoundTrips) {
  ModeSet set;
  set.dofs = {{101, 1}, {101, 3}, {102, -2}};
  Mode m;
  m.frequency_hz = 123.456;
  m.damping_ratio = 0.012;
  m.frequency_std_hz = 0.034;
  m.damping_ratio_std = 0.0007;
  m.mpc = 0.98;
  m.shape = Eigen::VectorXcd(3);
  m.shape << std::complex<double>(1.0, 0.1), std::complex<double>(-0.5, 0.0), std::complex<double>(0.25, -0.02);
  set.modes = {m, m};
  set.modes[1].frequency_hz = 234.5;
  const auto path = Write("roundtrip-modes.json", ModeSetJson(set).dump(2));
  const ModeSet back = ReadModeSet(path);
  ASSERT_EQ(back.modes.size(), 2u);
  ASSERT_EQ(back.dofs.size(), 3u);
  EXPECT_EQ(back.dofs[2].node, 102);
  EXPECT_EQ(back.dofs[2].direction, -2);
  EXPECT_DOUBLE_EQ(back.modes[0].frequency_hz, 123.456);
  EXPECT_DOUBLE_EQ(back.modes[1].frequency_hz, 234.5);
  EXPECT_DOUBLE_EQ(back.modes[0].damping_ratio, 0.012);
  EXPECT_DOUBLE_EQ(back.modes[0].frequency_std_hz, 0.034);  // the measured σ reaches the diagnosis
  EXPECT_DOUBLE_EQ(back.modes[0].damping_ratio_std, 0.0007);
  EXPECT_DOUBLE_EQ(back.modes[0].mpc, 0.98);
  for (int i = 0; i < 3; ++i) EXPECT_EQ(back.modes[0].shape(i), m.shape(i));
  EXPECT_EQ(back.source, path.string());
}

// Another tool's file: real shape values, DOFs in another order per mode, no σ, no damping.
TEST(ModesJson, RealShapesInAnyOrderAndNoSigma) {
  const ModeSet set = ReadModeSet(Write("other-tool.json", R"({"modes": [
    {"frequency_hz": 2.5, "shape": [{"node": 7, "dir": "+Z", "value": 1.0}, {"node": 9, "dir": "+Z", "value": -0.5}]},
    {"frequency_hz": 4.0, "shape": [{"node": 9, "dir": "Z", "value": 0.75}, {"node": 7, "dir": "+Z", "value": 0.25}]}]})"));
  ASSERT_EQ(set.modes.size(), 2u);
  EXPECT_EQ(set.dofs[0].node, 7);
  EXPECT_EQ(set.modes[1].shape(0), std::complex<double>(0.25, 0.0));
  EXPECT_EQ(set.modes[1].shape(1), std::complex<double>(0.75, 0.0));
  EXPECT_TRUE(std::isnan(set.modes[0].frequency_std_hz));
  EXPECT_EQ(set.modes[0].damping_ratio, 0.0);
}

TEST(ModesJson, BadInputNamesTheEntry) {
  EXPECT_NE(ErrorOf("{\"modes\": [\n{\"frequency_hz\": 1,,}]}").find("bad-modes.json:2: not valid JSON"), std::string::npos)
      << ErrorOf("{\"modes\": [\n{\"frequency_hz\": 1,,}]}");
  EXPECT_NE(ErrorOf(R"({"frequencies": []})").find("expected an object with a \"modes\" array"), std::string::npos);
  EXPECT_NE(ErrorOf(R"({"modes": []})").find("\"modes\" is empty"), std::string::npos);
  EXPECT_NE(ErrorOf(R"({"modes": [{"frequency_hz": -3, "shape": [{"node": 1, "dir": "+X", "value": 1}]}]})")
                .find("modes[0].frequency_hz: expected a frequency > 0 Hz"),
            std::string::npos);
  EXPECT_NE(ErrorOf(R"({"modes": [{"frequency_hz": 3, "shape": [{"node": 1, "dir": "+Q", "value": 1}]}]})")
                .find("modes[0].shape[0].dir: expected +X -X +Y -Y +Z -Z, found '+Q'"),
            std::string::npos);
  EXPECT_NE(ErrorOf(R"({"modes": [{"frequency_hz": 3, "shape": [{"node": 1, "dir": "+X", "value": [1]}]}]})")
                .find("modes[0].shape[0].value: expected [re, im] or a number"),
            std::string::npos);
  EXPECT_NE(ErrorOf(R"({"modes": [{"frequency_hz": 3, "frequency_std_hz": -1, "shape": [{"node": 1, "dir": "+X", "value": 1}]}]})")
                .find("frequency_std_hz: expected a 1σ >= 0 Hz"),
            std::string::npos);
  const std::string mismatch = ErrorOf(R"({"modes": [
    {"frequency_hz": 3, "shape": [{"node": 1, "dir": "+X", "value": 1}]},
    {"frequency_hz": 4, "shape": [{"node": 2, "dir": "+X", "value": 1}]}]})");
  EXPECT_NE(mismatch.find("modes[1].shape: DOF 2+X is not in modes[0]'s shape"), std::string::npos) << mismatch;
}

// The roving sets and the hammer DOF `ema fit --json` records beside the modes.
TEST(ModesJson, TestSetsRoundTrip) {
  FrfSet frfs;
  frfs.outputs = {{101, 1}, {101, 2}, {102, 1}, {103, 3}};
  frfs.references = {{101, -3}};
  frfs.output_sets = {0, 0, 0, 1};
  const nlohmann::json j = TestSetsJson(frfs);
  std::vector<std::vector<int>> sets;
  Dof reference;
  ASSERT_TRUE(ReadTestSets(j, &sets, &reference));
  ASSERT_EQ(sets.size(), 2u);
  EXPECT_EQ(sets[0], (std::vector<int>{101, 102}));
  EXPECT_EQ(sets[1], (std::vector<int>{103}));
  EXPECT_EQ(reference.node, 101);
  EXPECT_EQ(reference.direction, -3);
  frfs.output_sets.clear();  // unknown sets (another tool's FRFs): nothing recorded
  EXPECT_FALSE(ReadTestSets(TestSetsJson(frfs), &sets, &reference));
}

}  // namespace
}  // namespace ema::formats
