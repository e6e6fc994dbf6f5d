// One `ema run` of the guideway sample (samples/guideway), shared by every test that needs its
// results — in test_app (GuidewayRun) and test_diagnose (DiagnoseCli) — and by every ctest
// process: ctest runs each test in its own process, maybe in parallel, and the run is the slowest
// part of the suite under the sanitizers. The first process to take the lock runs it; the others
// wait, then reuse its output while the stamp (the ema executable and the sample's files) matches.
#pragma once

#include <fcntl.h>
#include <sys/file.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>

namespace ema::test {

/// FNV-1a of every file under `dir`, by relative path: enough to see any change to the sample.
inline std::map<std::string, std::uint64_t> HashTree(const std::filesystem::path& dir) {
  std::map<std::string, std::uint64_t> out;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(dir)) {
    if (!entry.is_regular_file()) continue;
    std::ifstream in(entry.path(), std::ios::binary);
    std::uint64_t h = 1469598103934665603ull;
    char buffer[65536];
    while (in.read(buffer, sizeof buffer) || in.gcount() > 0) {
      for (std::streamsize i = 0; i < in.gcount(); ++i) h = (h ^ static_cast<unsigned char>(buffer[i])) * 1099511628211ull;
      if (!in) break;
    }
    out[std::filesystem::relative(entry.path(), dir).string()] = h;
  }
  return out;
}

struct SharedGuidewayRun {
  std::filesystem::path out;                    ///< the run's output folder (with the report)
  std::filesystem::path log;                    ///< what the run printed
  std::map<std::string, std::uint64_t> before;  ///< the sample's files before the run
  int exit_code = -1;
};

/// The shared run (made now if no valid one exists). Throws std::runtime_error when the lock file
/// cannot be opened.
inline SharedGuidewayRun GuidewayRunOnce() {
  namespace fs = std::filesystem;
  const fs::path sample = fs::path(EMA_SOURCE_DIR) / "samples" / "guideway";
  const fs::path tmp(EMA_TEST_TMP_DIR);
  fs::create_directories(tmp);
  SharedGuidewayRun run{tmp / "guideway-run", tmp / "guideway-run.log", {}, -1};
  const fs::path stamp_file = tmp / "guideway-run.stamp", before_file = tmp / "guideway-run.before";
  const int lock = open((tmp / "guideway-run.lock").c_str(), O_CREAT | O_RDWR, 0644);
  if (lock < 0) throw std::runtime_error("cannot open " + (tmp / "guideway-run.lock").string());
  flock(lock, LOCK_EX);
  const std::map<std::string, std::uint64_t> files = HashTree(sample);
  // What a run of the sample depends on: the ema executable (size and modification time) and the
  // sample's files.
  std::ostringstream stamp;
  stamp << fs::file_size(EMA_EXECUTABLE) << " " << fs::last_write_time(EMA_EXECUTABLE).time_since_epoch().count();
  for (const auto& [file, h] : files) stamp << "\n" << file << " " << h;
  std::stringstream cached;
  if (std::ifstream in(stamp_file); in) cached << in.rdbuf();
  std::string cached_code;
  std::getline(cached, cached_code);
  const std::string cached_stamp = cached.str().substr(std::min(cached.str().size(), cached_code.size() + 1));
  if (!cached_code.empty() && cached_stamp == stamp.str()) {
    run.exit_code = std::stoi(cached_code);
    std::ifstream in(before_file);
    std::string file;
    std::uint64_t h = 0;
    while (in >> std::quoted(file) >> h) run.before[file] = h;
  } else {
    fs::remove(stamp_file);
    fs::remove_all(run.out);
    run.before = files;
    const std::string command = std::string(EMA_EXECUTABLE) + " run '" + (sample / "project.toml").string() + "' -o '" +
                                run.out.string() + "' > '" + run.log.string() + "' 2>&1";
    const int status = std::system(command.c_str());
    run.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    std::ofstream before(before_file);
    for (const auto& [f, h] : files) before << std::quoted(f) << " " << h << "\n";
    std::ofstream(stamp_file) << run.exit_code << "\n" << stamp.str();
  }
  flock(lock, LOCK_UN);
  close(lock);
  return run;
}

}  // namespace ema::test
