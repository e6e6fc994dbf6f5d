// Parallel UFF parsing (issue 18): a big file read on two threads gives exactly the datasets,
// notes and errors of a one-thread read.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <random>
#include <unistd.h>

#include "ema/core/error.hpp"
#include "ema/formats/uff.hpp"

namespace ema::formats::uff {
namespace {

namespace fs = std::filesystem;

fs::path TmpFile(const std::string& name) {
  const fs::path dir = fs::path(EMA_TEST_TMP_DIR) / ("uff_parallel_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  return dir / name;
}

// 60 datasets 58 (ASCII, single and double, real and complex), a 58b in the second half, a
// header 151 first and junk text between two datasets of the second half.
fs::path WriteMixedFile(const std::string& name) {
  std::mt19937 rng(5);
  std::normal_distribution<double> g(0.0, 1.0);
  std::vector<Dataset> datasets;
  Header151 header;
  header.model_name = "parallel test";
  datasets.push_back({151, 0, 0, {}, header});
  for (int k = 0; k < 60; ++k) {
    Function58 f;
    f.function_type = 4;
    f.response_node = k + 1;
    f.response_direction = 3;
    f.reference_node = 1;
    f.reference_direction = 3;
    f.ordinate_type = k % 3 == 0 ? 2 : k % 3 == 1 ? 5 : 6;
    f.count = 1500 + k;
    f.dx = 0.25;
    const int n = static_cast<int>(f.count) * (f.IsComplex() ? 2 : 1);
    for (int i = 0; i < n; ++i) f.y.push_back(g(rng));
    datasets.push_back({58, 0, 0, {}, f});
  }
  std::ofstream out(TmpFile(name), std::ios::binary);
  for (size_t k = 0; k < datasets.size(); ++k) {
    WriteOptions options;
    options.binary = k == 45;  // one 58b in the second half
    if (k == 50) out << "stray text between datasets\n";
    WriteDataset(out, datasets[k], options);
  }
  return TmpFile(name);
}

std::vector<Dataset> ReadAll(const fs::path& path, std::uint64_t parallel_min_bytes, std::vector<std::string>* notes,
                             bool* parallel = nullptr) {
  ReadOptions options;
  options.parallel_min_bytes = parallel_min_bytes;
  Reader reader(path, options);
  std::vector<Dataset> out;
  Dataset ds;
  while (reader.Next(&ds)) {
    EXPECT_LE(reader.Position(), reader.FileSize());
    out.push_back(std::move(ds));
  }
  *notes = reader.FileNotes();
  if (parallel) *parallel = reader.ServingParallelHalf();
  return out;
}

TEST(UffParallel, TwoThreadsGiveExactlyTheSequentialDatasets) {
  const fs::path path = WriteMixedFile("mixed.unv");
  std::vector<std::string> seq_notes, par_notes;
  bool seq_parallel = true, par_parallel = false;
  const auto seq = ReadAll(path, 0, &seq_notes, &seq_parallel);
  const auto par = ReadAll(path, 1, &par_notes, &par_parallel);  // any size: parallel
  EXPECT_FALSE(seq_parallel);
  EXPECT_TRUE(par_parallel) << "the second half must come from the worker (else this test proves nothing)";
  ASSERT_EQ(seq.size(), 61u);
  ASSERT_EQ(par.size(), seq.size());
  EXPECT_EQ(par_notes, seq_notes);
  EXPECT_FALSE(seq_notes.empty());  // the stray text is noted (with its line number)
  for (size_t k = 0; k < seq.size(); ++k) {
    EXPECT_EQ(par[k].number, seq[k].number) << k;
    EXPECT_EQ(par[k].line, seq[k].line) << k;
    EXPECT_EQ(par[k].offset, seq[k].offset) << k;
    EXPECT_EQ(par[k].notes, seq[k].notes) << k;
    if (seq[k].number == 58) {
      const auto& a = std::get<Function58>(seq[k].body);
      const auto& b = std::get<Function58>(par[k].body);
      EXPECT_EQ(a.y, b.y) << k;  // bit-exact values
      EXPECT_EQ(a.response_node, b.response_node) << k;
      EXPECT_EQ(a.binary, b.binary) << k;
    }
  }
}

TEST(UffParallel, ErrorInTheSecondHalfIsTheSequentialOne) {
  const fs::path good = WriteMixedFile("bad_base.unv");
  // Corrupt one value line of a dataset well past the middle: both reads must fail with the same
  // message (file, line, dataset, record).
  std::string text;
  {
    std::ifstream in(good, std::ios::binary);
    text.assign(std::istreambuf_iterator<char>(in), {});
  }
  size_t pos = text.size() * 3 / 4;
  pos = text.find("E", pos);
  ASSERT_NE(pos, std::string::npos);
  text[pos - 3] = 'x';
  const fs::path bad = TmpFile("bad.unv");
  std::ofstream(bad, std::ios::binary) << text;
  std::string seq_error, par_error;
  std::vector<std::string> notes;
  try {
    ReadAll(bad, 0, &notes);
  } catch (const InputError& e) {
    seq_error = e.what();
  }
  try {
    ReadAll(bad, 1, &notes);
  } catch (const InputError& e) {
    par_error = e.what();
  }
  EXPECT_FALSE(seq_error.empty());
  EXPECT_EQ(par_error, seq_error);
}

}  // namespace
}  // namespace ema::formats::uff
