// MATLAB .mat time data (formats/src/mat.cpp): files written here with matio itself (v5 and
// v7.3), read back sample for sample, and `ema frf` on a .mat giving the FRFs of the same
// records as UFF 58.
#include <matio.h>

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "acquisition/three_dof.hpp"
#include "ema/acquisition/simulator.hpp"
#include "ema/core/error.hpp"
#include "ema/formats/io.hpp"

namespace ema::formats {
namespace {

namespace fs = std::filesystem;

fs::path Dir(const std::string& name) {
  const fs::path dir = fs::path(EMA_TEST_TMP_DIR) / ("mat_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

void WriteDouble(mat_t* mat, const char* name, std::vector<size_t> dims, const std::vector<double>& values) {
  matvar_t* v = Mat_VarCreate(name, MAT_C_DOUBLE, MAT_T_DOUBLE, static_cast<int>(dims.size()), dims.data(),
                              const_cast<double*>(values.data()), 0);
  ASSERT_NE(v, nullptr);
  ASSERT_EQ(Mat_VarWrite(mat, v, MAT_COMPRESSION_NONE), 0);
  Mat_VarFree(v);
}

void WriteText(mat_t* mat, const char* name, const std::string& text) {
  size_t dims[2] = {1, text.size()};
  matvar_t* v = Mat_VarCreate(name, MAT_C_CHAR, MAT_T_UTF8, 2, dims, const_cast<char*>(text.data()), 0);
  ASSERT_NE(v, nullptr);
  ASSERT_EQ(Mat_VarWrite(mat, v, MAT_COMPRESSION_NONE), 0);
  Mat_VarFree(v);
}

void WriteCell(mat_t* mat, const char* name, const std::vector<std::string>& texts) {
  size_t dims[2] = {1, texts.size()};
  matvar_t* cell = Mat_VarCreate(name, MAT_C_CELL, MAT_T_CELL, 2, dims, nullptr, 0);
  ASSERT_NE(cell, nullptr);
  for (size_t i = 0; i < texts.size(); ++i) {
    size_t d[2] = {1, texts[i].size()};
    // MAT_F_DONT_COPY_DATA is not set: matio copies the text into the cell element.
    Mat_VarSetCell(cell, static_cast<int>(i), Mat_VarCreate(nullptr, MAT_C_CHAR, MAT_T_UTF8, 2, d,
                                                             const_cast<char*>(texts[i].data()), 0));
  }
  ASSERT_EQ(Mat_VarWrite(mat, cell, MAT_COMPRESSION_NONE), 0);
  Mat_VarFree(cell);
}

/// force: n × impacts, response: n × channels × impacts, in MATLAB's column-major order.
void WriteMat(const fs::path& path, enum mat_ft version, double fs_hz, size_t n, size_t impacts,
              const std::vector<double>& force, const std::vector<double>& response, const std::string& reference,
              const std::vector<std::string>& channels, const std::string& quantity = "", size_t columns = 0) {
  if (columns == 0) columns = channels.size();
  ASSERT_EQ(response.size(), n * columns * impacts);
  mat_t* mat = Mat_CreateVer(path.string().c_str(), nullptr, version);
  ASSERT_NE(mat, nullptr);
  WriteDouble(mat, "fs", {1, 1}, {fs_hz});
  WriteDouble(mat, "force", {n, impacts}, force);
  if (impacts > 1) WriteDouble(mat, "response", {n, columns, impacts}, response);
  else WriteDouble(mat, "response", {n, columns}, response);
  WriteText(mat, "reference", reference);
  WriteCell(mat, "channels", channels);
  if (!quantity.empty()) WriteText(mat, "quantity", quantity);
  Mat_Close(mat);
}

TEST(MatTimeData, ReadsV5AndV73SampleForSample) {
  const fs::path dir = Dir("roundtrip");
  const size_t n = 64, impacts = 2;
  std::vector<double> force(n * impacts), response(n * 3 * impacts);
  for (size_t i = 0; i < force.size(); ++i) force[i] = 0.5 * static_cast<double>(i) - 3.25;
  for (size_t i = 0; i < response.size(); ++i) response[i] = std::sin(0.1 * static_cast<double>(i)) * 1e-3;
  for (auto version : {MAT_FT_MAT5, MAT_FT_MAT73}) {
    const fs::path path = dir / (version == MAT_FT_MAT5 ? "v5.mat" : "v73.mat");
    WriteMat(path, version, 2048.0, n, impacts, force, response, "1+Z", {"1+Z", "2-X", "3:+Y"}, "velocity");
    const auto records = ReadTimeRecords(path);  // dispatched by the MATLAB header
    ASSERT_EQ(records.size(), impacts * 4) << path;
    // Order: per impact the force, then the channels.
    const TimeRecord& f2 = records[4];
    EXPECT_EQ(f2.quantity, Quantity::kForce);
    EXPECT_EQ(f2.impact, 2);
    EXPECT_EQ(f2.channel, (Dof{1, 3}));
    EXPECT_DOUBLE_EQ(f2.sample_interval_s, 1.0 / 2048.0);
    ASSERT_EQ(f2.samples.size(), n);
    EXPECT_EQ(f2.samples[0], force[n]);  // column 2 of force, bit for bit
    const TimeRecord& r = records[6];     // impact 2, channel 2
    EXPECT_EQ(r.channel, (Dof{2, -1}));
    EXPECT_EQ(r.reference, (Dof{1, 3}));
    EXPECT_EQ(r.quantity, Quantity::kVelocity);
    EXPECT_EQ(r.unit, "m/s");
    EXPECT_EQ(r.samples[5], response[(1 * 3 + 1) * n + 5]);
    EXPECT_EQ(records[7].channel, (Dof{3, 2}));
  }
}

TEST(MatTimeData, ErrorsNameTheVariable) {
  const fs::path dir = Dir("errors");
  const size_t n = 16;
  std::vector<double> force(n, 1.0), response(n * 2, 0.5);
  WriteMat(dir / "wrong.mat", MAT_FT_MAT5, 1000.0, n, 1, force, response, "1+Z", {"1+Z", "2+Z", "3+Z"}, "", 2);
  try {
    ReadTimeRecords(dir / "wrong.mat");
    FAIL() << "three channels for two response columns must fail";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("variable 'response'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("wrong.mat"), std::string::npos) << e.what();
  }
  WriteMat(dir / "dof.mat", MAT_FT_MAT5, 1000.0, n, 1, force, response, "hammer", {"1+Z", "2+Z"});
  EXPECT_THROW(ReadTimeRecords(dir / "dof.mat"), InputError);
  mat_t* mat = Mat_CreateVer((dir / "nofs.mat").string().c_str(), nullptr, MAT_FT_MAT5);
  WriteDouble(mat, "force", {n, 1}, force);
  Mat_Close(mat);
  try {
    ReadTimeRecords(dir / "nofs.mat");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("'fs'"), std::string::npos) << e.what();
  }
}

TEST(MatTimeData, EmaFrfOnMatEqualsUff) {
  // A simulated 3-DOF hammer test (hammer at 1+Z, 5 impacts) written as UFF 58 and as .mat.
  const fs::path dir = Dir("frf");
  const auto sys = testing::MakeThreeDof();
  acquisition::HammerTestPlan plan;
  plan.references = {{1, 3}};
  plan.roving_sets = {{{1, 3}, {2, 3}, {3, 3}}};
  plan.samples_per_record = 4096;
  plan.impacts_per_reference = 3;
  plan.response_noise = 0.01;
  const auto records = acquisition::SimulateHammerTestSets({sys.truth}, plan)[0].records;
  WriteTimeRecords(dir / "test.unv", records);
  const size_t n = 4096, impacts = 3;
  std::vector<double> force(n * impacts), response(n * 3 * impacts);
  for (const TimeRecord& r : records) {
    ASSERT_EQ(r.samples.size(), n);
    const size_t k = static_cast<size_t>(r.impact - 1);
    double* dst = r.quantity == Quantity::kForce ? &force[k * n] : &response[(k * 3 + (r.channel.node - 1)) * n];
    std::copy(r.samples.begin(), r.samples.end(), dst);
  }
  WriteMat(dir / "test.mat", MAT_FT_MAT5, plan.sample_rate_hz, n, impacts, force, response, "1+Z", {"1+Z", "2+Z", "3+Z"});
  for (const char* name : {"test.unv", "test.mat"}) {
    const std::string cmd = std::string("\"") + EMA_EXECUTABLE + "\" frf \"" + (dir / name).string() + "\" -o \"" +
                            (dir / (std::string(name) + ".frf.unv")).string() + "\" > /dev/null 2>&1";
    ASSERT_EQ(std::system(cmd.c_str()), 0) << name;
  }
  const FrfSet a = ReadFrfSet(dir / "test.unv.frf.unv"), b = ReadFrfSet(dir / "test.mat.frf.unv");
  ASSERT_EQ(a.h.size(), 1u);
  ASSERT_EQ(b.h.size(), 1u);
  ASSERT_EQ(a.h[0].rows(), b.h[0].rows());
  ASSERT_EQ(a.outputs, b.outputs);
  // The UFF time file stores the samples to 13 significant digits (E20.12), the .mat holds them
  // exactly: the FRFs agree to that rounding (4e-11 of the largest |H| here; 1e-9 leaves room).
  const double scale = a.h[0].cwiseAbs().maxCoeff();
  EXPECT_LT((a.h[0] - b.h[0]).cwiseAbs().maxCoeff(), 1e-9 * scale);
}

}  // namespace
}  // namespace ema::formats
