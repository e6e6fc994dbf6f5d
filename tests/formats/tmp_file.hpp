// A scratch file path under the tests' temporary folder (created on first use), shared by the
// formats tests that write a file and read it back.
#pragma once

#include <filesystem>
#include <string>

namespace ema::formats::test {

inline std::filesystem::path TmpFile(const std::string& name) {
  std::filesystem::create_directories(EMA_TEST_TMP_DIR);
  return std::filesystem::path(EMA_TEST_TMP_DIR) / name;
}

}  // namespace ema::formats::test
