// Dataset 2412 (elements: test-geometry lines and faces, FE meshes) decoded from the RawDataset
// the reader keeps, so a file is still copied through byte for byte.
//
// Records per element (I-DEAS/SDRC 2412):
//   1    6I10 element label, FE descriptor id, physical property table number, material
//        property table number, colour, number of nodes;
//   2    3I10 beam-type elements only (rods, beams, pipes): orientation node, fore-end and
//        aft-end cross-section numbers;
//   2/3  8I10 node labels, eight per line, on as many lines as the node count needs.
#include <algorithm>
#include <string>

#include "ema/core/error.hpp"
#include "ema/formats/uff.hpp"
#include "uff_lexer.hpp"

namespace ema::formats::uff {

bool HasBeamRecord2412(int fe_descriptor) {
  switch (fe_descriptor) {
    case 11:  // rod
    case 21:  // linear beam
    case 22:  // tapered beam
    case 23:  // curved beam
    case 24:  // parabolic beam
    case 31:  // straight pipe
    case 32:  // curved pipe
      return true;
    default:
      return false;
  }
}

Elements2412 DecodeElements2412(const RawDataset& raw, const std::string& file, std::int64_t delimiter_line) {
  const auto& lines = raw.lines;  // lines[0] is the dataset-number line, one below the delimiter
  auto where = [&](size_t k) { return file + ":" + std::to_string(delimiter_line + 1 + static_cast<std::int64_t>(k)); };
  constexpr size_t kLabelsPerLine = 8;
  Elements2412 out;
  size_t k = 1;
  while (k < lines.size()) {
    if (Trim(lines[k]).empty()) {  // trailing blank lines before the end delimiter
      ++k;
      continue;
    }
    const auto r1 = LineIntegers(lines[k], where(k), "dataset 2412 record 1", 6);
    if (r1.size() != 6)
      throw InputError(where(k), "dataset 2412 record 1: expected 6 integers (label, FE descriptor, physical and "
                                 "material property, colour, node count), got " + std::to_string(r1.size()));
    Element2412 e;
    e.label = r1[0];
    e.fe_descriptor = static_cast<int>(r1[1]);
    e.physical_property = r1[2];
    e.material_property = r1[3];
    e.colour = static_cast<int>(r1[4]);
    const std::int64_t count = r1[5];
    const std::string element = "dataset 2412 element " + std::to_string(e.label);
    if (e.label <= 0) throw InputError(where(k), element + ": the element label must be positive");
    if (count < 1) throw InputError(where(k), element + ": " + std::to_string(count) + " nodes, expected at least 1");
    ++k;
    if (HasBeamRecord2412(e.fe_descriptor)) {
      if (k >= lines.size())
        throw InputError(where(k - 1), element + ": ends before its beam record (orientation node, cross sections)");
      const auto r2 = LineIntegers(lines[k], where(k), element + " beam record", 3);
      if (r2.size() != 3)
        throw InputError(where(k), element + " beam record: expected 3 integers (orientation node, fore- and "
                                   "aft-end cross section), got " + std::to_string(r2.size()));
      e.beam_orientation_node = r2[0];
      e.beam_fore_cross_section = r2[1];
      e.beam_aft_cross_section = r2[2];
      ++k;
    }
    // The node count is checked against the lines that are there, never trusted for an allocation.
    while (static_cast<std::int64_t>(e.nodes.size()) < count) {
      if (k >= lines.size())
        throw InputError(where(k - 1), element + ": " + std::to_string(e.nodes.size()) + " of " +
                                           std::to_string(count) + " node labels before the end of the dataset");
      const auto labels = LineIntegers(lines[k], where(k), element + " node labels", 1);
      const std::int64_t expected = std::min<std::int64_t>(count - static_cast<std::int64_t>(e.nodes.size()), kLabelsPerLine);
      if (static_cast<std::int64_t>(labels.size()) != expected)
        throw InputError(where(k), element + " node labels: expected " + std::to_string(expected) +
                                       " on this line (8 per line, " + std::to_string(count) + " in all), got " +
                                       std::to_string(labels.size()));
      e.nodes.insert(e.nodes.end(), labels.begin(), labels.end());
      ++k;
    }
    out.elements.push_back(std::move(e));
  }
  return out;
}

}  // namespace ema::formats::uff
