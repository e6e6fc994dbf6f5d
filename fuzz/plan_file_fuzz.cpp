// libFuzzer target: the test plan of `ema simulate` (docs/plan-format.md), read through the
// command itself (formats::ReadPlanFile and the checks of the plan against the model) beside a fixed model without
// [[point]]: every plan that reads is then refused at its first DOF, so no simulation runs and
// each input stays fast. Any byte string gives an ema::InputError (or, never, a written file),
// never a crash, hang, leak, undefined behaviour or other exception.
#include <cstdint>
#include <string>
#include <vector>

#include "cli.hpp"
#include "ema/core/error.hpp"
#include "fuzz_util.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const auto model = ema::fuzz::WriteScratch(
      "model.toml",
      "[model]\nname = \"block\"\n[[body]]\nname = \"block\"\nmass = 1.0\ninertia = [0.01, 0.01, 0.01]\n"
      "[[spring]]\nname = \"s\"\na = { body = \"block\" }\ndirection = \"+Z\"\nlaw = { linear = { k = 1.0e6 } }\n");
  const auto plan = ema::fuzz::WriteScratch("plan.toml", {reinterpret_cast<const char*>(data), size});
  const std::vector<std::string> args = {model.string(), "--plan", plan.string(), "-o",
                                         (ema::fuzz::ScratchDir() / "out.unv").string()};
  try {
    ema::RunSimulate(args);
  } catch (const ema::InputError&) {
  } catch (const ema::ConvergenceError&) {  // a plan whose time integration cannot converge: exit 3
  }
  return 0;
}
