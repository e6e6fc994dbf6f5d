// libFuzzer target: the JSON writers whose output ema reads back, written then read.
//  * MODES.json: ModeSetJson / FitModesJson (`ema model --json`, `ema fit --json`) → file →
//    ReadModeSet (MODES.json: formats/src/modes_json.cpp). A set the reader's rules accept (cli.md: f > 0
//    finite, damping in [0, 1) or not finite, finite shape values, DOFs with a node > 0 and a
//    named direction, each once) must read back with every number equal (the writer prints
//    doubles to the shortest round-trip form) and every non-finite optional value as NaN (written
//    null; a non-finite damping ratio reads as 0); any other set must give an ema::InputError.
//  * the roving sets: TestSetsJson → dump → parse → ReadTestSets gives the sets (nodes in first-
//    seen order per set, sets by id) and the reference back.
// A mismatch traps; a crash, UBSan report, leak or any other exception is a finding.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <map>
#include <nlohmann/json.hpp>
#include <set>

#include "ema/core/error.hpp"
#include "ema/formats/io.hpp"
#include "ema/formats/json_codecs.hpp"
#include "fuzz_util.hpp"
#include "json_fuzz_gen.hpp"

namespace {

using ema::fuzz::Gen;
using nlohmann::json;

[[noreturn]] void Fail(const char* what, std::size_t mode = 0) {
  std::fprintf(stderr, "round trip: %s (mode %zu)\n", what, mode);
  __builtin_trap();
}

// NaN-aware equality: equal numbers, or both not a number.
bool Same(double a, double b) { return a == b || (std::isnan(a) && std::isnan(b)); }
double Written(double v) { return std::isfinite(v) ? v : ema::kNaN; }  // what null reads back as

// Values from the reader's own domain more often than not, so that most sets are readable.
double Frequency(Gen& g) { return g.Bool() ? 0.5 + g.Int(0, 1 << 20) / 64.0 : g.Double(); }
double Ratio(Gen& g) { return g.Bool() ? g.Int(0, 999) / 1000.0 : g.Double(); }

bool Readable(const ema::ModeSet& set) {
  if (set.modes.empty() || set.dofs.empty()) return false;
  std::set<ema::Dof> seen;
  for (const ema::Dof& d : set.dofs) {
    if (d.node <= 0 || d.direction == 0 || std::abs(d.direction) > 6) return false;
    if (!seen.insert(d).second) return false;
  }
  for (const ema::Mode& m : set.modes) {
    if (!(m.frequency_hz > 0.0) || !std::isfinite(m.frequency_hz)) return false;
    if (std::isfinite(m.damping_ratio) && !(m.damping_ratio >= 0.0 && m.damping_ratio < 1.0)) return false;
    if (std::isfinite(m.frequency_std_hz) && !(m.frequency_std_hz >= 0.0)) return false;
    for (const double f : m.set_frequency_hz)
      if (!std::isfinite(f)) return false;  // written null: the reader requires a number
    for (Eigen::Index i = 0; i < m.shape.size(); ++i)
      if (!std::isfinite(m.shape[i].real()) || !std::isfinite(m.shape[i].imag())) return false;
  }
  return true;
}

void CompareModes(const ema::ModeSet& in, const ema::ModeSet& out) {
  if (out.modes.size() != in.modes.size()) Fail("mode count");
  if (out.dofs != in.dofs) Fail("DOFs");
  for (std::size_t r = 0; r < in.modes.size(); ++r) {
    const ema::Mode& a = in.modes[r];
    const ema::Mode& b = out.modes[r];
    if (a.frequency_hz != b.frequency_hz) Fail("frequency_hz", r);
    if (!Same(std::isfinite(a.damping_ratio) ? a.damping_ratio : 0.0, b.damping_ratio)) Fail("damping_ratio", r);
    if (!Same(Written(a.frequency_std_hz), b.frequency_std_hz)) Fail("frequency_std_hz", r);
    if (!Same(Written(a.damping_ratio_std), b.damping_ratio_std)) Fail("damping_ratio_std", r);
    if (!Same(Written(a.mpc), b.mpc)) Fail("mpc", r);
    if (!Same(Written(a.mpd), b.mpd)) Fail("mpd_deg", r);
    if (!Same(Written(a.frequency_spread_hz), b.frequency_spread_hz)) Fail("frequency_spread_hz", r);
    if (b.shape.size() != a.shape.size()) Fail("shape size", r);
    for (Eigen::Index i = 0; i < a.shape.size(); ++i)
      if (a.shape[i] != b.shape[i]) Fail("shape value", r);
    const std::size_t sets = a.set_frequency_hz.size();
    if (b.set_frequency_hz.size() != sets || b.set_damping_ratio.size() != sets || b.set_frequency_std_hz.size() != sets)
      Fail("sets", r);
    for (std::size_t k = 0; k < sets; ++k) {
      if (a.set_frequency_hz[k] != b.set_frequency_hz[k]) Fail("sets.frequency_hz", r);
      const double d = k < a.set_damping_ratio.size() ? Written(a.set_damping_ratio[k]) : ema::kNaN;
      const double s = k < a.set_frequency_std_hz.size() ? Written(a.set_frequency_std_hz[k]) : ema::kNaN;
      if (!Same(d, b.set_damping_ratio[k])) Fail("sets.damping_ratio", r);
      if (!Same(s, b.set_frequency_std_hz[k])) Fail("sets.frequency_std_hz", r);
    }
  }
}

void ModesRoundTrip(Gen& g) {
  ema::ModeSet set;
  // DOFs: mostly readable ones (a node > 0, a named direction), sometimes anything.
  set.dofs.resize(g.Count(g.Bool() ? 12 : 400));
  for (ema::Dof& d : set.dofs) d = g.Bool() ? ema::Dof{g.Int(1, 40), g.Int(-6, 6)} : g.AnyDof();
  if (g.Bool()) {  // most sets have each DOF once
    std::set<ema::Dof> seen;
    std::erase_if(set.dofs, [&](const ema::Dof& d) { return !seen.insert(d).second; });
  }
  const std::size_t n = set.dofs.size();
  set.modes.resize(g.Count(std::min<std::size_t>(30, 1200 / std::max<std::size_t>(n, 1))));
  for (ema::Mode& m : set.modes) {
    g.FillMode(&m, n);
    if (g.Bool()) m.frequency_hz = Frequency(g);
    if (g.Bool()) m.damping_ratio = Ratio(g);
    if (g.Bool()) m.frequency_std_hz = Ratio(g);
    if (g.Bool())
      for (Eigen::Index i = 0; i < m.shape.size(); ++i) m.shape[i] = {g.Int(-1000, 1000) / 7.0, Ratio(g)};
    if (g.Bool())
      for (double& f : m.set_frequency_hz) f = Frequency(g);
  }
  json j;
  if (g.Bool()) {
    j = ema::formats::ModeSetJson(set);
  } else {
    ema::curvefit::FitResult fit;
    fit.modes = set;
    fit.selected.resize(g.Count(set.modes.size()));
    fit.selection_rule = g.Text();
    j = ema::formats::FitModesJson(fit, ema::curvefit::RefineMethod::kMl);
  }
  const auto path = ema::fuzz::WriteScratch("modes.json", j.dump(g.Bool() ? 2 : -1));
  const bool readable = Readable(set);
  ema::ModeSet back;
  try {
    back = ema::formats::ReadModeSet(path);  // a file starting with { is MODES.json
  } catch (const ema::InputError& e) {
    if (readable) {
      std::fprintf(stderr, "%s\n", e.what());
      Fail("the reader refused what the writer wrote");
    }
    return;
  }
  if (!readable) Fail("the reader accepted a set outside its rules");
  CompareModes(set, back);
}

void TestSetsRoundTrip(Gen& g) {
  ema::FrfSet frfs;
  frfs.outputs.resize(g.Count(600));
  for (ema::Dof& d : frfs.outputs) d = g.Bool() ? ema::Dof{g.Int(1, 50), g.Int(1, 3)} : g.AnyDof();
  frfs.references.resize(g.Count(3));
  for (ema::Dof& d : frfs.references) d = g.AnyDof();
  frfs.output_sets.resize(g.Bool() ? frfs.outputs.size() : g.Count(frfs.outputs.size() + 2));
  for (int& s : frfs.output_sets) s = g.Bool() ? g.Int(0, 5) : g.AnyInt();
  const json j = json::parse(ema::formats::TestSetsJson(frfs).dump());
  std::vector<std::vector<int>> sets;
  ema::Dof reference{-1, 99};
  const bool read = ema::formats::ReadTestSets(j, &sets, &reference);
  const bool written = !frfs.output_sets.empty() && frfs.output_sets.size() == frfs.outputs.size();
  if (!written) {
    if (read) Fail("roving sets read where none were written");
    return;
  }
  std::map<int, std::vector<int>> expected;
  bool valid = true;
  for (std::size_t o = 0; o < frfs.outputs.size(); ++o) {
    std::vector<int>& nodes = expected[frfs.output_sets[o]];
    if (std::find(nodes.begin(), nodes.end(), frfs.outputs[o].node) == nodes.end()) nodes.push_back(frfs.outputs[o].node);
    valid = valid && frfs.outputs[o].node > 0;
  }
  if (read != valid) Fail(valid ? "written roving sets not read" : "roving sets with a node <= 0 read");
  if (!read) return;
  std::vector<std::vector<int>> want;
  for (auto& [id, nodes] : expected) want.push_back(nodes);
  if (sets != want) Fail("roving sets differ");
  if (frfs.references.size() == 1) {
    const ema::Dof& r = frfs.references[0];
    const int dir = std::abs(r.direction) <= 6 ? r.direction : 0;  // "?7" reads as no direction
    if (reference != ema::Dof{r.node, dir}) Fail("reference");
  } else if (reference != ema::Dof{-1, 99}) {
    Fail("a reference read where none was written");
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  Gen g(data, size);
  if (g.Int(0, 3) == 0)
    TestSetsRoundTrip(g);
  else
    ModesRoundTrip(g);
  return 0;
}
