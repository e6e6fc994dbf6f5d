// The bad-input corpus (tests/badinput/, table cases.tsv): one test per case. Each runs `ema` on
// a copy of the case in a scratch folder and asserts the exit code, that stderr holds every
// expected fragment (the file, the line/record, what was expected), that the case's files are
// untouched and, for errors, that no output was left behind.
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

namespace ema {
namespace {

namespace fs = std::filesystem;

const fs::path kCorpus = fs::path(EMA_SOURCE_DIR) / "tests" / "badinput";

struct BadInputCase {
  std::string name;      // file or folder in tests/badinput
  int exit_code = 1;
  std::string command;   // CASE and OUT placeholders
  std::vector<std::string> fragments;
};

std::string Replace(std::string s, const std::string& from, const std::string& to) {
  for (std::size_t p = s.find(from); p != std::string::npos; p = s.find(from, p + to.size())) s.replace(p, from.size(), to);
  return s;
}

std::vector<BadInputCase> ReadCases() {
  std::vector<BadInputCase> cases;
  std::ifstream in(kCorpus / "cases.tsv");
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::vector<std::string> cols;
    std::stringstream s(line);
    for (std::string c; std::getline(s, c, '\t');) cols.push_back(c);
    if (cols.size() != 4) continue;  // CorpusTable.EveryRowIsWellFormed reports it
    BadInputCase c{cols[0], std::stoi(cols[1]), cols[2], {}};
    for (std::size_t p = 0;;) {
      const std::size_t q = cols[3].find(" && ", p);
      c.fragments.push_back(cols[3].substr(p, q == std::string::npos ? std::string::npos : q - p));
      if (q == std::string::npos) break;
      p = q + 4;
    }
    cases.push_back(c);
  }
  return cases;
}

std::map<std::string, std::string> Files(const fs::path& dir) {
  std::map<std::string, std::string> out;
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    if (!e.is_regular_file()) continue;
    std::ifstream in(e.path(), std::ios::binary);
    std::ostringstream s;
    s << in.rdbuf();
    out[fs::relative(e.path(), dir).string()] = s.str();
  }
  return out;
}

class BadInput : public ::testing::TestWithParam<BadInputCase> {};

TEST_P(BadInput, ExitCodeMessageAndNoOutputLeft) {
  const BadInputCase& c = GetParam();
  const fs::path work = fs::path(EMA_TEST_TMP_DIR) / ("badinput-" + std::to_string(getpid())) / c.name;
  fs::remove_all(work);
  fs::create_directories(work);
  const fs::path source = kCorpus / c.name;
  ASSERT_TRUE(fs::exists(source)) << source;
  if (fs::is_directory(source)) fs::copy(source, work / c.name, fs::copy_options::recursive);
  else fs::copy_file(source, work / c.name);
  fs::copy_file(kCorpus / "all_free.toml", work / "all_free.toml", fs::copy_options::skip_existing);  // for correlate
  const auto before = Files(work);

  const std::string args = Replace(Replace(c.command, "CASE", c.name), "OUT", "out");
  const fs::path log = work.parent_path() / (c.name + ".log");
  const std::string command =
      "cd '" + work.string() + "' && " + std::string(EMA_EXECUTABLE) + " " + args + " > /dev/null 2> '" + log.string() + "'";
  const int status = std::system(command.c_str());
  const int code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  std::ifstream in(log);
  const std::string err((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());

  SCOPED_TRACE("ema " + args + "\n" + err);
  EXPECT_EQ(code, c.exit_code);
  for (const std::string& f : c.fragments) EXPECT_NE(err.find(f), std::string::npos) << "missing: " << f;
  const auto after = Files(work);
  for (const auto& [name, bytes] : before) {
    ASSERT_TRUE(after.count(name)) << name << " vanished";
    EXPECT_TRUE(after.at(name) == bytes) << name << " changed";
  }
  if (c.exit_code != 0) {
    for (const auto& [name, bytes] : after) EXPECT_TRUE(before.count(name)) << "output left behind: " << name;
  }
  if (!HasFailure()) fs::remove_all(work);
}

std::string CaseName(const ::testing::TestParamInfo<BadInputCase>& info) {
  std::string n = info.param.name;
  for (char& ch : n)
    if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
  return n;
}

INSTANTIATE_TEST_SUITE_P(Corpus, BadInput, ::testing::ValuesIn(ReadCases()), CaseName);

// The table is the test list: at least 40 cases (issue #11), every row well formed, every file
// of the corpus used by a row.
TEST(BadInputTable, EveryFileHasOneWellFormedRow) {
  std::ifstream in(kCorpus / "cases.tsv");
  std::string line;
  int rows = 0;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    EXPECT_EQ(std::count(line.begin(), line.end(), '\t'), 3) << line;
    ++rows;
  }
  const auto cases = ReadCases();
  EXPECT_EQ(static_cast<int>(cases.size()), rows);
  EXPECT_GE(rows, 40);
  for (const auto& entry : fs::directory_iterator(kCorpus)) {
    const std::string name = entry.path().filename().string();
    if (name == "cases.tsv" || name == "all_free.toml" || name == "README.md") continue;
    EXPECT_TRUE(std::any_of(cases.begin(), cases.end(), [&](const BadInputCase& c) { return c.name == name; }))
        << name << " has no row in cases.tsv";
  }
}

}  // namespace
}  // namespace ema
