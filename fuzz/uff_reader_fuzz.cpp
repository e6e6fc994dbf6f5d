// libFuzzer target: the UFF reader must answer any byte string with datasets or an
// ema::InputError, never a crash, hang or other exception. Each input is written to a temp
// file because the reader is file based (streaming, 58b seeks).
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <unistd.h>

#include "ema/core/error.hpp"
#include "ema/formats/uff.hpp"

namespace {

const std::filesystem::path& InputPath() {
  static const std::filesystem::path p =
      std::filesystem::temp_directory_path() / ("ema_fuzz_uff_" + std::to_string(getpid()) + ".uff");
  return p;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  {
    std::ofstream out(InputPath(), std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  }
  for (bool headers_only : {false, true}) {
    try {
      ema::formats::uff::ReadOptions options;
      options.headers_only = headers_only;
      options.allow_truncated = size % 2 == 1;
      options.allow_non_finite = size % 3 == 1;
      ema::formats::uff::Reader reader(InputPath(), options);
      ema::formats::uff::Dataset d;
      int n = 0;
      while (reader.Next(&d) && ++n < 10000) {
      }
    } catch (const ema::InputError&) {
      // expected for malformed input
    }
  }
  return 0;
}
