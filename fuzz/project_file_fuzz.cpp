// libFuzzer target: the project file of `ema run` (docs/project-file.md) with the model and
// time-data files it names (parts of the input, fuzz_util.hpp: project.toml, model.toml, t.unv),
// and its model file as `ema run` reads it. Any byte string gives a project or an ema::InputError, never
// a crash, hang, leak, undefined behaviour or other exception.
#include <cstdint>

#include "ema/core/error.hpp"
#include "fuzz_util.hpp"
#include "ema/formats/model_file.hpp"
#include "ema/formats/project_file.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto parts = ema::fuzz::SplitParts(data, size, 3);
  ema::fuzz::WriteParts(parts, {"project.toml", "model.toml", "t.unv"});
  try {
    ema::formats::ReadProjectFile(ema::fuzz::ScratchDir() / "project.toml");
  } catch (const ema::InputError&) {
  }
  try {
    ema::formats::ReadModelFile(ema::fuzz::ScratchDir() / "model.toml");  // the project's model, as `ema run` reads it
  } catch (const ema::InputError&) {
  }
  return 0;
}
