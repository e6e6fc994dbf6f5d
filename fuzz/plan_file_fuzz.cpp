// libFuzzer target: the test plan of `ema simulate` (docs/plan-format.md), read the way the command
// reads it (formats::ReadPlanFile, then the stage's checks of the plan against the model) beside
// a fixed model without [[point]]: every plan that reads is then refused at its first DOF, so no
// simulation runs and each input stays fast. The command line and the model are the same for
// every input, so they are parsed once (RunSimulate's own argument parsing and model read cost
// four fifths of each run and saw nothing of the input). Any byte string gives an ema::InputError
// (or, never, a written file), never a crash, hang, leak, undefined behaviour or other exception.
#include <cstdint>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "ema/core/error.hpp"
#include "ema/formats/model_file.hpp"
#include "ema/formats/plan_file.hpp"
#include "fuzz_util.hpp"
#include "stages.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const auto model_path = ema::fuzz::WriteScratch(
      "model.toml",
      "[model]\nname = \"block\"\n[[body]]\nname = \"block\"\nmass = 1.0\ninertia = [0.01, 0.01, 0.01]\n"
      "[[spring]]\nname = \"s\"\na = { body = \"block\" }\ndirection = \"+Z\"\nlaw = { linear = { k = 1.0e6 } }\n");
  const auto plan_path = ema::fuzz::WriteScratch("plan.toml", {reinterpret_cast<const char*>(data), size});
  static const std::optional<ema::app::SimulateConfig> config = ema::app::ParseSimulateArgs(
      {model_path.string(), "--plan", plan_path.string(), "-o", (ema::fuzz::ScratchDir() / "out.unv").string()});
  static const ema::model::Model model = ema::formats::ReadModelFile(model_path);
  try {
    std::ostringstream out;
    ema::app::RunSimulateStage(*config, model, ema::formats::ReadPlanFile(plan_path), out);
  } catch (const ema::InputError&) {
  } catch (const ema::ConvergenceError&) {  // a plan whose time integration cannot converge: exit 3
  }
  return 0;
}
