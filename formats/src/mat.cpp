// MATLAB .mat hammer-test time data (v5, v7 and v7.3 files through matio), in the variable
// convention of docs/formats.md ("MATLAB .mat time data").
#include <matio.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "ema/core/error.hpp"
#include "ema/formats/io.hpp"
#include "ema/formats/uff.hpp"
#include "text_cells.hpp"

namespace ema::formats {

namespace {

using text::Lower;
using text::ParseDofText;  // the FRF-table convention of docs/formats.md

struct MatCloser {
  void operator()(mat_t* m) const { Mat_Close(m); }
};
struct VarFreer {
  void operator()(matvar_t* v) const { Mat_VarFree(v); }
};
using MatFile = std::unique_ptr<mat_t, MatCloser>;
using MatVar = std::unique_ptr<matvar_t, VarFreer>;

size_t Elements(const matvar_t* v) {
  size_t n = 1;
  for (int k = 0; k < v->rank; ++k) n *= v->dims[k];
  return n;
}

std::string DimsText(const matvar_t* v) {
  std::string s;
  for (int k = 0; k < v->rank; ++k) s += (k ? "x" : "") + std::to_string(v->dims[k]);
  return s;
}

/// Real numeric values of a variable in MATLAB's (column-major) order.
std::vector<double> Numbers(const matvar_t* v, const std::string& where) {
  const std::string name = v->name ? v->name : "?";
  if (v->isComplex) throw InputError(where, "variable '" + name + "': complex values, expected real samples");
  const size_t n = Elements(v);
  std::vector<double> out(n);
  auto copy = [&](auto tag) {
    using T = decltype(tag);
    const T* p = static_cast<const T*>(v->data);
    for (size_t i = 0; i < n; ++i) out[i] = static_cast<double>(p[i]);
  };
  if (n > 0 && !v->data) throw InputError(where, "variable '" + name + "': no data");
  switch (v->class_type) {
    case MAT_C_DOUBLE: copy(double{}); break;
    case MAT_C_SINGLE: copy(float{}); break;
    case MAT_C_INT8: copy(std::int8_t{}); break;
    case MAT_C_UINT8: copy(std::uint8_t{}); break;
    case MAT_C_INT16: copy(std::int16_t{}); break;
    case MAT_C_UINT16: copy(std::uint16_t{}); break;
    case MAT_C_INT32: copy(std::int32_t{}); break;
    case MAT_C_UINT32: copy(std::uint32_t{}); break;
    case MAT_C_INT64: copy(std::int64_t{}); break;
    case MAT_C_UINT64: copy(std::uint64_t{}); break;
    default: throw InputError(where, "variable '" + name + "': expected a numeric array");
  }
  for (size_t i = 0; i < n; ++i)
    if (!std::isfinite(out[i]))
      throw InputError(where, "variable '" + name + "': value " + std::to_string(i + 1) + " is not finite");
  return out;
}

/// A char array (one row) as text.
std::string Text(const matvar_t* v, const std::string& where) {
  const std::string name = v->name ? v->name : "?";
  if (v->class_type != MAT_C_CHAR) throw InputError(where, "variable '" + name + "': expected text (a char array)");
  const size_t n = Elements(v);
  std::string out;
  if (!v->data) return out;
  for (size_t i = 0; i < n; ++i) {
    unsigned code = 0;
    switch (v->data_type) {
      case MAT_T_UINT16:
      case MAT_T_UTF16: code = static_cast<const std::uint16_t*>(v->data)[i]; break;
      case MAT_T_UINT32:
      case MAT_T_UTF32: code = static_cast<const std::uint32_t*>(v->data)[i]; break;
      default: code = static_cast<const unsigned char*>(v->data)[i]; break;
    }
    out += code < 128 ? static_cast<char>(code) : '?';
  }
  while (!out.empty() && std::isspace(static_cast<unsigned char>(out.back()))) out.pop_back();
  return out;
}

/// A cell array of char, or a char matrix with one name per row.
std::vector<std::string> TextList(const matvar_t* v, const std::string& where) {
  std::vector<std::string> out;
  if (v->class_type == MAT_C_CELL) {
    const size_t n = Elements(v);
    for (size_t i = 0; i < n; ++i) {
      matvar_t* cell = Mat_VarGetCell(const_cast<matvar_t*>(v), static_cast<int>(i));
      if (!cell) throw InputError(where, "variable 'channels': cell " + std::to_string(i + 1) + " is empty");
      out.push_back(Text(cell, where));
    }
    return out;
  }
  if (v->class_type == MAT_C_CHAR && v->rank == 2) {
    const size_t rows = v->dims[0], cols = v->dims[1];
    const std::string all = [&] {
      std::string s;
      const size_t n = rows * cols;
      for (size_t i = 0; i < n; ++i) s += v->data ? static_cast<const char*>(v->data)[i] : ' ';
      return s;
    }();
    for (size_t r = 0; r < rows; ++r) {
      std::string name;
      for (size_t c = 0; c < cols; ++c) name += all[c * rows + r];
      while (!name.empty() && name.back() == ' ') name.pop_back();
      out.push_back(name);
    }
    return out;
  }
  throw InputError(where, "variable 'channels': expected a cell array of DOF names such as {'1+Z', '2+Z'}");
}

}  // namespace

bool LooksLikeMat(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  char head[128] = {};
  in.read(head, sizeof head);
  const std::string h(head, static_cast<size_t>(in.gcount()));
  // v5/v7 files open with a 116-byte text header "MATLAB 5.0 MAT-file"; v7.3 files are HDF5 with
  // the same text in a 512-byte user block (the HDF5 signature follows at byte 512).
  return h.rfind("MATLAB 5.0 MAT-file", 0) == 0 || h.rfind("MATLAB 7.3 MAT-file", 0) == 0;
}

std::vector<TimeRecord> ReadMatTimeRecords(const std::filesystem::path& path) {
  const std::string where = path.string();
  MatFile mat(Mat_Open(path.string().c_str(), MAT_ACC_RDONLY));
  if (!mat) throw InputError(where, "not a readable MATLAB .mat file");
  std::map<std::string, MatVar> vars;
  {
    // Names first (Mat_VarReadNextInfo), then the data of the variables the convention uses.
    std::set<std::string> names;
    while (matvar_t* info = Mat_VarReadNextInfo(mat.get())) {
      if (info->name) names.insert(info->name);
      Mat_VarFree(info);
    }
    for (const char* name : {"fs", "dt", "force", "response", "reference", "channels", "quantity", "force_unit",
                             "response_unit"})
      if (names.count(name)) {
        vars[name] = MatVar(Mat_VarRead(mat.get(), name));
        if (!vars[name]) throw InputError(where, std::string("variable '") + name + "' cannot be read");
      }
  }
  auto need = [&](const char* name, const char* what) -> const matvar_t* {
    const auto it = vars.find(name);
    if (it == vars.end())
      throw InputError(where, std::string("no variable '") + name + "' (" + what +
                                  "); the .mat convention is in docs/formats.md (fs, force, response, reference, channels)");
    return it->second.get();
  };

  double dt = 0.0;
  if (vars.count("fs")) {
    const auto v = Numbers(vars["fs"].get(), where);
    if (v.size() != 1 || !(v[0] > 0.0)) throw InputError(where, "variable 'fs': expected one positive sampling rate in Hz");
    dt = 1.0 / v[0];
  } else if (vars.count("dt")) {
    const auto v = Numbers(vars["dt"].get(), where);
    if (v.size() != 1 || !(v[0] > 0.0)) throw InputError(where, "variable 'dt': expected one positive sample interval in s");
    dt = v[0];
  } else {
    throw InputError(where, "no sampling rate: expected a variable 'fs' [Hz] or 'dt' [s]");
  }

  const matvar_t* force = need("force", "the hammer's force, samples x impacts");
  const matvar_t* response = need("response", "the responses, samples x channels [x impacts]");
  const auto reference = ParseDofText(Text(need("reference", "the hammer DOF, e.g. '1+Z'"), where));
  if (!reference) throw InputError(where, "variable 'reference': expected a DOF such as '1+Z' or '101:-X'");
  const auto channel_names = TextList(need("channels", "the response DOFs, e.g. {'1+Z', '2+Z'}"), where);
  std::vector<Dof> channels;
  for (size_t c = 0; c < channel_names.size(); ++c) {
    const auto dof = ParseDofText(channel_names[c]);
    if (!dof) throw InputError(where, "variable 'channels': entry " + std::to_string(c + 1) + " '" + channel_names[c] +
                                          "' is not a DOF such as '2+Z'");
    channels.push_back(*dof);
  }

  Quantity quantity = Quantity::kAcceleration;
  std::string response_unit = "m/s^2";
  if (vars.count("quantity")) {
    const std::string q = Lower(Text(vars["quantity"].get(), where));
    if (q == "acceleration" || q == "acc") quantity = Quantity::kAcceleration;
    else if (q == "velocity" || q == "vel") quantity = Quantity::kVelocity, response_unit = "m/s";
    else if (q == "displacement" || q == "disp") quantity = Quantity::kDisplacement, response_unit = "m";
    else throw InputError(where, "variable 'quantity': expected acceleration, velocity or displacement, got '" + q + "'");
  }
  if (vars.count("response_unit")) response_unit = Text(vars["response_unit"].get(), where);
  const std::string force_unit = vars.count("force_unit") ? Text(vars["force_unit"].get(), where) : "N";

  // force: samples x impacts (a vector is one impact); response: samples x channels [x impacts].
  if (force->rank != 2) throw InputError(where, "variable 'force': expected samples x impacts, got " + DimsText(force));
  const bool force_row = force->dims[0] == 1 && force->dims[1] > 1;
  const size_t n = force_row ? force->dims[1] : force->dims[0];
  const size_t impacts = force_row ? 1 : force->dims[1];
  if (n < 2) throw InputError(where, "variable 'force': at least 2 samples needed");
  const size_t nc = channels.size();
  const size_t r_impacts = response->rank >= 3 ? response->dims[2] : 1;
  if (response->rank > 3 || response->dims[0] != n || response->dims[1] != nc || r_impacts != impacts)
    throw InputError(where, "variable 'response': expected " + std::to_string(n) + "x" + std::to_string(nc) +
                                (impacts > 1 ? "x" + std::to_string(impacts) : std::string()) +
                                " (samples x channels x impacts, as 'force' and 'channels' say), got " + DimsText(response));
  const std::vector<double> f = Numbers(force, where), r = Numbers(response, where);

  std::vector<TimeRecord> out;
  const std::string file = path.filename().string();
  for (size_t k = 0; k < impacts; ++k) {
    TimeRecord fr;
    fr.channel = *reference;
    fr.reference = *reference;
    fr.impact = static_cast<int>(k + 1);
    fr.quantity = Quantity::kForce;
    fr.sample_interval_s = dt;
    fr.samples.assign(f.begin() + static_cast<std::ptrdiff_t>(k * n), f.begin() + static_cast<std::ptrdiff_t>((k + 1) * n));
    fr.unit = force_unit;
    fr.origin = file + ", variable 'force', impact " + std::to_string(k + 1);
    out.push_back(std::move(fr));
    for (size_t c = 0; c < nc; ++c) {
      TimeRecord rr;
      rr.channel = channels[c];
      rr.reference = *reference;
      rr.impact = static_cast<int>(k + 1);
      rr.quantity = quantity;
      rr.sample_interval_s = dt;
      const size_t start = (k * nc + c) * n;
      rr.samples.assign(r.begin() + static_cast<std::ptrdiff_t>(start), r.begin() + static_cast<std::ptrdiff_t>(start + n));
      rr.unit = response_unit;
      rr.origin = file + ", variable 'response', channel " + std::to_string(c + 1) + " (" + DofName(channels[c]) +
                  "), impact " + std::to_string(k + 1);
      out.push_back(std::move(rr));
    }
  }
  return out;
}

}  // namespace ema::formats
