#pragma once
// Helpers the CLI tests share: reading a file back and running `ema` with its output captured.
// One definition here, not one per test file (the test executables are unity builds, in which
// two same-named helpers of two files would collide).

#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace ema::test {

/// The whole file, byte for byte ("" when it cannot be opened).
inline std::string Slurp(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

/// Runs `ema ARGS` with its standard output in DIR/stdout.txt and its errors in DIR/stderr.txt;
/// returns its exit status (-1 when it did not exit).
inline int RunEma(const std::string& args, const std::filesystem::path& dir) {
  const std::string command = std::string(EMA_EXECUTABLE) + " " + args + " > '" + (dir / "stdout.txt").string() +
                              "' 2> '" + (dir / "stderr.txt").string() + "'";
  const int status = std::system(command.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

}  // namespace ema::test
