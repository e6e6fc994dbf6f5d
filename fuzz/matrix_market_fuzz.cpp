// libFuzzer target: the Matrix Market reader (and the symmetry check of [fe] matrices) answer
// any byte string with a matrix or an ema::InputError, never a crash, hang, leak, undefined
// behaviour, huge allocation from a lying size line, or other exception.
#include <cstdint>

#include "ema/core/error.hpp"
#include "ema/formats/matrix_market.hpp"
#include "fuzz_util.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto path = ema::fuzz::WriteScratch("K.mtx", {reinterpret_cast<const char*>(data), size});
  try {
    const Eigen::SparseMatrix<double> m = ema::formats::ReadMatrixMarket(path);
    ema::formats::RequireSymmetric(m, path);
  } catch (const ema::InputError&) {
  }
  return 0;
}
