// What a UFF file written by WriteFrfSet / WriteModeSet holds, without writing or reading it:
// the writer's datasets with every number at the precision of its field (Fortran E13.5 holds six
// significant digits, E20.12 thirteen; 58b doubles are exact) and ID lines cut to 80 columns,
// assembled by the reader's own code (io_internal.hpp). `ema run` hands these on from stage to
// stage, so each stage gets exactly what the subcommand reading the file gets.
// tests/formats/stored_view_test.cpp pins them to the real write-and-read round trip.
#include <algorithm>
#include <cmath>
#include <utility>

#include "ema/formats/io.hpp"
#include "ema/formats/uff.hpp"
#include "io_internal.hpp"

namespace ema::formats {

namespace {

// `value` as written with FormatE(width, precision) and parsed back.
double AsWritten(double value, int width, int precision) {
  double parsed = value;
  uff::ParseReal(uff::FormatE(value, width, precision), &parsed);
  return parsed;
}

// An ID line as written (80 columns, trailing blanks dropped, "NONE" when empty).
std::string IdAsWritten(const std::string& text) {
  std::string out = text.substr(0, text.find_first_of("\r\n"));
  while (!out.empty() && out.back() == ' ') out.pop_back();
  if (out.size() > 80) out.resize(80);
  return out.empty() ? "NONE" : out;
}

void ToWrittenPrecision(uff::Function58* f, bool binary) {
  for (std::string& id : f->id) id = IdAsWritten(id);
  f->x_min = AsWritten(f->x_min, 13, 5);
  f->dx = AsWritten(f->dx, 13, 5);
  f->z = AsWritten(f->z, 13, 5);
  if (binary) {
    if (!f->IsDouble())
      for (double& v : f->y) v = static_cast<float>(v);
    return;
  }
  for (double& v : f->x) v = AsWritten(v, 13, 5);
  for (double& v : f->y) v = f->IsDouble() ? AsWritten(v, 20, 12) : AsWritten(v, 13, 5);
}

}  // namespace

FrfSet StoredFrfSet(const FrfSet& frfs, const WriteOptions& options) {
  std::vector<Function58At> functions, coherences;
  for (uff::Dataset& d : FrfSetDatasets(frfs)) {
    auto& f = std::get<uff::Function58>(d.body);
    ToWrittenPrecision(&f, options.binary);
    (f.function_type == 4 ? functions : coherences).push_back({std::move(f), 0});
  }
  return FrfSetFromFunctions("FRF set", std::move(functions), std::move(coherences));
}

ModeSet StoredModeSet(const ModeSet& modes, const std::filesystem::path& path) {
  std::vector<uff::Dataset> datasets = ModeSetDatasets(modes);
  for (uff::Dataset& d : datasets) {
    if (auto* a = std::get_if<uff::Data55>(&d.body)) {
      for (std::string& id : a->id) id = IdAsWritten(id);
      for (double& v : a->reals) v = AsWritten(v, 13, 5);
      for (auto& node : a->nodes)
        for (double& v : node.values) v = AsWritten(v, 13, 5);
    } else if (auto* n = std::get_if<uff::Nodes15>(&d.body)) {
      for (auto& node : n->nodes)
        for (double& v : node.xyz) v = AsWritten(v, 13, 5);
    }
  }
  return ModeSetFromDatasets(path, datasets);
}

}  // namespace ema::formats
