// cli.md "Every command: outputs never replace inputs": for every command and every output
// option, an output that names one of the command's inputs (directly, as ./x, through a symlink
// or a `..` detour, or a file a model/project names) is refused with exit 2 before anything is
// read or written: the input keeps its bytes and mtime and no file appears beside it.
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>

#include "test_files.hpp"

namespace ema {
namespace {

namespace fs = std::filesystem;

const fs::path kSource = fs::path(EMA_SOURCE_DIR);

using test::Slurp;

struct Snapshot {
  std::map<std::string, std::pair<std::string, fs::file_time_type>> files;  // bytes, mtime
};

Snapshot Take(const fs::path& dir) {
  Snapshot s;
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    if (e.is_symlink() || !e.is_regular_file()) continue;
    s.files[fs::relative(e.path(), dir).string()] = {Slurp(e.path()), fs::last_write_time(e.path())};
  }
  return s;
}

class OutputsSpareInputs : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::path(EMA_TEST_TMP_DIR) / ("spare-" + std::string(info->name()) + "-" + std::to_string(getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "frfdir");
    fs::copy_file(kSource / "samples/guideway/data/stud-5um.unv", dir_ / "time.unv");
    fs::copy_file(kSource / "samples/guideway/data/stud-9um.unv", dir_ / "time2.unv");
    fs::copy_file(kSource / "samples/uff/dataset58_FRF.unv", dir_ / "frf.unv");
    fs::copy_file(kSource / "samples/uff/dataset58_FRF.unv", dir_ / "frf.svg");  // an FRF file with a picture's name
    for (const char* f : {"carriage.toml", "film25.csv", "plan.toml"}) fs::copy_file(kSource / "tests/model/data" / f, dir_ / f);
    for (int i = 1; i <= 3; ++i) {
      const std::string name = "meas_point_" + std::to_string(i) + ".txt";
      fs::copy_file(kSource / "samples/meas-point" / name, dir_ / "frfdir" / name);
    }
    fs::create_symlink("time.unv", dir_ / "link.unv");
    // Test modes for correlate/diagnose: the model's own modes (any valid UFF 55 would do).
    ASSERT_EQ(Ema("model carriage.toml -o modes.unv"), 0) << output_;
    fs::copy_file(dir_ / "modes.unv", dir_ / "modes.csv");  // modes under a table's name
  }
  void TearDown() override {
    if (!HasFailure()) fs::remove_all(dir_);
  }

  int Ema(const std::string& args) {
    const fs::path log = dir_.parent_path() / (dir_.filename().string() + ".log");
    const std::string command =
        "cd '" + dir_.string() + "' && " + std::string(EMA_EXECUTABLE) + " " + args + " > '" + log.string() + "' 2>&1";
    const int status = std::system(command.c_str());
    output_ = Slurp(log);
    fs::remove(log);
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  }

  // Runs `args`, expects exit 2 with a message naming `output` and `input`, and no change at all
  // in the folder (bytes, mtimes, no new or missing file).
  void ExpectRefused(const std::string& args, const std::string& output, const std::string& input) {
    SCOPED_TRACE("ema " + args);
    const Snapshot before = Take(dir_);
    EXPECT_EQ(Ema(args), 2) << output_;
    EXPECT_NE(output_.find("refused"), std::string::npos) << output_;
    EXPECT_NE(output_.find(output), std::string::npos) << "message names the output: " << output_;
    EXPECT_NE(output_.find(input), std::string::npos) << "message names the input: " << output_;
    const Snapshot after = Take(dir_);
    ASSERT_EQ(after.files.size(), before.files.size()) << "a file appeared or vanished";
    for (const auto& [name, data] : before.files) {
      ASSERT_TRUE(after.files.count(name)) << name;
      EXPECT_TRUE(after.files.at(name).first == data.first) << name << " changed";
      EXPECT_TRUE(after.files.at(name).second == data.second) << name << " mtime changed";
    }
  }

  fs::path dir_;
  std::string output_;
};

TEST_F(OutputsSpareInputs, Info) {
  ExpectRefused("info time.unv --json time.unv", "time.unv", "time.unv");
  ExpectRefused("info time.unv --json ./time.unv", "./time.unv", "time.unv");
  ExpectRefused("info link.unv --json time.unv", "time.unv", "link.unv");  // input through a symlink
}

TEST_F(OutputsSpareInputs, Frf) {
  ExpectRefused("frf time.unv -o time.unv", "-o time.unv", "time.unv");
  ExpectRefused("frf time.unv -o out.unv --json time.unv", "--json time.unv", "time.unv");
  ExpectRefused("frf time.unv time2.unv -o frfdir/../time2.unv", "frfdir/../time2.unv", "time2.unv");
  ExpectRefused("frf time.unv -o link.unv", "link.unv", "time.unv");                         // output is a link to it
  fs::create_hard_link(dir_ / "time2.unv", dir_ / "hard.unv");
  ExpectRefused("frf time2.unv -o hard.unv", "hard.unv", "time2.unv");                       // a hard link to it
  ExpectRefused("frf time.unv -o \"$PWD/time.unv\"", "/time.unv", "time.unv");               // absolute path
  ExpectRefused("frf time.unv -o out.unv --json out.unv", "--json out.unv", "-o out.unv");  // two outputs, one file
}

TEST_F(OutputsSpareInputs, Fit) {
  ExpectRefused("fit frf.unv -o frf.unv", "-o frf.unv", "frf.unv");
  ExpectRefused("fit frf.unv -o m.unv --json ./frf.unv", "--json ./frf.unv", "frf.unv");
  ExpectRefused("fit frf.unv -o m.unv --stabilisation frf.unv", "--stabilisation frf.unv", "frf.unv");
  ExpectRefused("fit frf.svg -o m.unv --plot frf.svg", "--plot frf.svg", "frf.svg");
  ExpectRefused("fit frfdir -o frfdir/meas_point_2.txt", "meas_point_2.txt", "frfdir");  // a file of the input folder
}

TEST_F(OutputsSpareInputs, Model) {
  ExpectRefused("model carriage.toml -o carriage.toml", "-o carriage.toml", "carriage.toml");
  ExpectRefused("model carriage.toml -o m.unv --json film25.csv", "--json film25.csv", "film25.csv");  // a curve it names
}

TEST_F(OutputsSpareInputs, Correlate) {
  ExpectRefused("correlate modes.unv carriage.toml --json modes.unv", "--json modes.unv", "modes.unv");
  ExpectRefused("correlate modes.csv carriage.toml --table modes.csv", "--table modes.csv", "modes.csv");
  ExpectRefused("correlate modes.unv carriage.toml --table film25.csv", "--table film25.csv", "carriage.toml");
}

TEST_F(OutputsSpareInputs, Diagnose) {
  ExpectRefused("diagnose carriage.toml --test modes.unv -o carriage.toml", "-o carriage.toml", "carriage.toml");
  ExpectRefused("diagnose carriage.toml --test S=modes.unv --json modes.unv", "--json modes.unv", "modes.unv");
  ExpectRefused("diagnose carriage.toml --test modes.unv -o film25.csv", "-o film25.csv", "film25.csv");
}

TEST_F(OutputsSpareInputs, DiagnoseForceLevels) {
  ExpectRefused("diagnose carriage.toml --test modes.unv --force-level 10=modes.unv --force-level 20=modes.csv --json modes.csv",
                "--json modes.csv", "modes.csv");
}

TEST_F(OutputsSpareInputs, Amplitude) {
  ExpectRefused("amplitude --level 10=modes.unv --level 20=modes.csv --json modes.unv", "--json modes.unv", "modes.unv");
  ExpectRefused("amplitude --level 10=modes.unv --level 20=modes.csv --report ./modes.csv", "--report ./modes.csv", "modes.csv");
}

TEST_F(OutputsSpareInputs, FrfForceBins) {
  // The bin files FRF.binK.unv are outputs too: -o frf.unv with 2 bins writes frf.bin2.unv.
  fs::copy_file(dir_ / "time2.unv", dir_ / "frf.bin2.unv");
  ExpectRefused("frf time.unv frf.bin2.unv -o frf.unv --force-bins 2", "frf.bin2.unv", "frf.bin2.unv");
  ExpectRefused("frf time.unv frf.bin2.unv -o frf.unv --force-bin-edges 10,50,200", "frf.bin2.unv", "frf.bin2.unv");
}

TEST_F(OutputsSpareInputs, Simulate) {
  ExpectRefused("simulate carriage.toml --plan plan.toml -o plan.toml", "-o plan.toml", "plan.toml");
  ExpectRefused("simulate carriage.toml --plan plan.toml -o carriage.toml", "-o carriage.toml", "carriage.toml");
  ExpectRefused("simulate carriage.toml --plan plan.toml -o film25.csv", "-o film25.csv", "film25.csv");
}

TEST_F(OutputsSpareInputs, Run) {
  fs::create_directories(dir_ / "out" / "beam");
  fs::copy_file(dir_ / "time.unv", dir_ / "out" / "beam" / "frf.unv");
  std::ofstream(dir_ / "project.toml") << "[project]\nmodel = \"carriage.toml\"\n[[test]]\nname = \"beam\"\n"
                                           "time = [\"out/beam/frf.unv\"]\n";
  ExpectRefused("run project.toml -o out", "out/beam/frf.unv", "project.toml");  // run's FRF file is its time data
  ExpectRefused("run project.toml -o project.toml", "-o project.toml", "project.toml");  // OUTDIR is the project
  std::ofstream(dir_ / "project2.toml") << "[project]\nmodel = \"out/updated-model.toml\"\n[[test]]\nname = \"beam\"\n"
                                            "frf = \"frf.unv\"\n";
  fs::copy_file(dir_ / "carriage.toml", dir_ / "out" / "updated-model.toml");
  ExpectRefused("run project2.toml -o out", "updated-model.toml", "project2.toml");
}

// Not too eager: distinct outputs beside the inputs are written as before.
TEST_F(OutputsSpareInputs, DistinctOutputsAreWritten) {
  EXPECT_EQ(Ema("info time.unv --json info.json"), 0) << output_;
  EXPECT_TRUE(fs::exists(dir_ / "info.json"));
  EXPECT_EQ(Ema("model carriage.toml -o m2.unv --json m2.json"), 0) << output_;
  EXPECT_TRUE(fs::exists(dir_ / "m2.json"));
}

}  // namespace
}  // namespace ema
