// libFuzzer target: `ema fe-import`'s readers and the import with its checks (formats/fe_import.hpp):
// a CalculiX nominal run (nominal.sti, .mas, .dof) and one part's run (a.sti, .mas, .dof), the
// deck's element sets (deck.inp) and an Abaqus matrix (part.mtx), each a part of the input
// (fuzz_util.hpp). Every input must give an import or an ema::InputError naming the file — never
// a crash, hang, leak, undefined behaviour or other exception.
#include <cstdint>
#include <optional>

#include "ema/core/error.hpp"
#include "ema/formats/fe_import.hpp"
#include "fuzz_util.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace ema::formats;
  const auto parts = ema::fuzz::SplitParts(data, size, 8);
  ema::fuzz::WriteParts(parts, {"nominal.sti", "nominal.mas", "nominal.dof", "a.sti", "a.mas", "a.dof", "deck.inp", "part.mtx"});
  const auto& dir = ema::fuzz::ScratchDir();
  std::optional<FeElementSets> sets;
  try {
    sets = ReadInpElementSets(dir / "deck.inp");
  } catch (const ema::InputError&) {
  }
  const FeRun nominal{FeRun::Code::kCalculix, dir / "nominal.sti", dir / "nominal.mas", dir / "nominal.dof"};
  FePartInput a;
  a.name = "A";
  a.run = {FeRun::Code::kCalculix, dir / "a.sti", dir / "a.mas", dir / "a.dof"};
  try {
    (void)ImportFeParts(nominal, {a}, {}, {}, sets ? &*sets : nullptr);
  } catch (const ema::InputError&) {
  }
  try {
    (void)ReadAbaqusMatrix(dir / "part.mtx");
  } catch (const ema::InputError&) {
  }
  return 0;
}
