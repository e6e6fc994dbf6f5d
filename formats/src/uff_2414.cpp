// Dataset 2414 (analysis data, as FE tools export results) decoded as its dataset-55 equivalent,
// so that normal and complex modes from Simcenter/NX, Permas, ... read as a ModeSet.
//
// Records (I-DEAS/SDRC 2414, data at nodes):
//   1 I10 analysis dataset label;  2 40A1 name;  3 I10 dataset location (1 = data at nodes,
//   2 = on elements, 3 = at nodes on elements, 5 = at points);  4-8 ID lines;
//   9 6I10 model type, analysis type (2 normal mode, 3/7 complex eigenvalue, ...), data
//     characteristic (1 scalar, 2 3-DOF translation, 3 6-DOF), result type (8 displacement,
//     11 velocity, 12 acceleration, ...), data type (2/4 real, 5/6 complex), values per node;
//  10 8I10 design set, iteration, solution set, boundary condition, load set, mode number,
//     time step, frequency number;  11 2I10 creation option, number retained;
//  12 6E13.5 time, frequency, eigenvalue, modal mass, viscous damping ratio, hysteretic damping;
//  13 6E13.5 Re/Im eigenvalue, Re/Im modal A, Re/Im modal B;
//  then per node: I10 node label, and its values (complex: re, im interleaved) on 6 per line
//  (single precision) or however many the line holds (the reader takes them by count).
#include <string>

#include "ema/core/error.hpp"
#include "ema/formats/uff.hpp"
#include "uff_lexer.hpp"

namespace ema::formats::uff {

namespace {

std::string Record(int record) { return "dataset 2414 record " + std::to_string(record); }

}  // namespace

bool Decode2414AsData55(const RawDataset& raw, const std::string& where, Data55* out) {
  const auto& L = raw.lines;  // L[0] is the dataset-number line
  if (L.size() < 14) throw InputError(where, "dataset 2414: " + std::to_string(L.size()) + " lines, expected at least 14 records");
  const auto location = LineIntegers(L[3], where, Record(3), 1);
  if (location[0] != 1) return false;  // element or point data: not a nodal shape
  const auto r9 = LineIntegers(L[9], where, Record(9), 6);
  const auto r10 = LineIntegers(L[10], where, Record(10), 6);
  Data55 d;
  for (int k = 0; k < 5; ++k) d.id[k] = std::string(Trim(L[4 + k]));
  d.model_type = static_cast<int>(r9[0]);
  d.analysis_type = static_cast<int>(r9[1]);
  d.data_characteristic = static_cast<int>(r9[2]);
  d.specific_data_type = static_cast<int>(r9[3]);
  d.data_type = static_cast<int>(r9[4]);
  d.ndv = static_cast<int>(r9[5]);
  if (d.analysis_type != 2 && d.analysis_type != 3 && d.analysis_type != 7) return false;  // not modes
  if (d.specific_data_type != 8 && d.specific_data_type != 11 && d.specific_data_type != 12) return false;  // stresses, ...
  if (d.ndv < 1 || d.ndv > 6)
    throw InputError(where, "dataset 2414 record 9 field 6: " + std::to_string(d.ndv) + " values per node, expected 1..6");
  if (d.data_type != 2 && d.data_type != 4 && d.data_type != 5 && d.data_type != 6)
    throw InputError(where, "dataset 2414 record 9 field 5: data type " + std::to_string(d.data_type) + ", expected 2, 4, 5 or 6");
  // Record 12/13 (their line count is fixed at one each in single precision; double-precision
  // writers may use two lines each: take 6 numbers per record whatever the layout).
  size_t line = 12;
  auto take = [&](size_t count, int record) {
    std::vector<double> v;
    while (v.size() < count) {
      if (line >= L.size()) throw InputError(where, "dataset 2414 record " + std::to_string(record) + ": ends early");
      const auto more = LineReals(L[line++], where, Record(record));
      v.insert(v.end(), more.begin(), more.end());
    }
    return v;
  };
  const auto r12 = take(6, 12);
  const auto r13 = take(6, 13);
  if (d.analysis_type == 2) {
    // Dataset 55 normal mode reals: frequency, modal mass, viscous damping ratio, hysteretic damping.
    d.reals = {r12[1], r12[3], r12[4], r12[5]};
  } else {
    // Dataset 55 complex eigenvalue reals: Re/Im eigenvalue, Re/Im modal A, Re/Im modal B.
    d.reals = {r13[0], r13[1], r13[2], r13[3], r13[4], r13[5]};
  }
  d.integers = {r10[4], r10[5]};  // load case, mode number (as dataset 55 record 7)
  const size_t per_node = static_cast<size_t>(d.IsComplex() ? 2 * d.ndv : d.ndv);
  while (line < L.size()) {
    if (Trim(L[line]).empty()) {
      ++line;
      continue;
    }
    const auto label = LineIntegers(L[line], where, Record(14), 1);
    ++line;
    Data55::NodeValues nv;
    nv.node = label[0];
    nv.values = take(per_node, 15);
    nv.values.resize(per_node);
    d.nodes.push_back(std::move(nv));
  }
  *out = std::move(d);
  return true;
}

}  // namespace ema::formats::uff
