// libFuzzer target: the model file (TOML, model-format.md) with the files it names: a curve
// (a.csv), [fe] matrices (M.mtx, K.mtx), DOF map (dofs.csv) and node list (nodes.csv), each a
// part of the input (fuzz_util.hpp). Reading, and solving a model that reads, must answer with
// a model / modes or an ema::InputError, never a crash, hang, leak, undefined behaviour or
// other exception. Models of more than 60 DOFs are read but not solved (time per input).
#include <cstdint>

#include "ema/core/error.hpp"
#include "ema/formats/model_file.hpp"
#include "ema/model/solve.hpp"
#include "fuzz_util.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto parts = ema::fuzz::SplitParts(data, size, 6);
  ema::fuzz::WriteParts(parts, {"model.toml", "a.csv", "M.mtx", "K.mtx", "dofs.csv", "nodes.csv"});
  try {
    const ema::model::Model m = ema::formats::ReadModelFile(ema::fuzz::ScratchDir() / "model.toml");
    if (m.bodies.size() * 6 + m.fe.dofs.size() <= 60 && m.springs.size() <= 60) {
      ema::model::SolveOptions options;
      if (!m.setups.empty()) options.setup = m.setups.front().name;
      ema::model::Solve(m, options);
    }
  } catch (const ema::InputError&) {
  }
  return 0;
}
