// libFuzzer target: the UFF reader must answer any byte string with datasets or an
// ema::InputError, never a crash, hang, leak, undefined behaviour or other exception. Each input
// is written to a scratch file because the reader is file based (streaming, 58b seeks). The
// file-level entry points (time data, FRFs, modes, `ema info`'s summary) run on it too.
#include <cstdint>

#include "ema/core/error.hpp"
#include "ema/formats/info.hpp"
#include "ema/formats/io.hpp"
#include "ema/formats/uff.hpp"
#include "fuzz_util.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto path = ema::fuzz::WriteScratch("input.uff", {reinterpret_cast<const char*>(data), size});
  for (bool headers_only : {false, true}) {
    try {
      ema::formats::uff::ReadOptions options;
      options.headers_only = headers_only;
      options.allow_truncated = size % 2 == 1;
      options.allow_non_finite = size % 3 == 1;
      ema::formats::uff::Reader reader(path, options);
      ema::formats::uff::Dataset d;
      int n = 0;
      while (reader.Next(&d) && ++n < 10000) {
      }
    } catch (const ema::InputError&) {
      // expected for malformed input
    }
  }
  try {
    ema::formats::SummarizeFile(path);
  } catch (const ema::InputError&) {
  }
  try {
    ema::formats::ReadTimeRecords(path);
  } catch (const ema::InputError&) {
  }
  try {
    ema::formats::ReadFrfSet(path);
  } catch (const ema::InputError&) {
  }
  try {
    ema::formats::ReadModeSet(path);
  } catch (const ema::InputError&) {
  }
  return 0;
}
