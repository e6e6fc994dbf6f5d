// libFuzzer target: CSV hammer time data (docs/formats.md) and the one-complex-value-per-line
// column text (the frf-meas-point files) answer any byte string with records or an
// ema::InputError, never a crash, hang, leak, undefined behaviour or other exception.
#include <cstdint>

#include "ema/core/error.hpp"
#include "ema/formats/io.hpp"
#include "fuzz_util.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  // The impact number comes from the file name when there is no impact column.
  const auto path = ema::fuzz::WriteScratch("point3_impact4.csv", bytes);
  try {
    ema::formats::ReadCsvTimeRecords(path);
  } catch (const ema::InputError&) {
  }
  try {
    ema::formats::ReadComplexColumnText(path);
  } catch (const ema::InputError&) {
  }
  return 0;
}
