#include "run_history.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "ema/formats/atomic_file.hpp"
#include "ema/formats/model_file.hpp"
#include "ema/model/effects.hpp"

namespace ema::app {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

json Number(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

}  // namespace

std::string FileHash(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) return "";
  std::uint64_t h = 1469598103934665603ull;
  char c;
  while (in.get(c)) {
    h ^= static_cast<unsigned char>(c);
    h *= 1099511628211ull;
  }
  char buffer[17];
  std::snprintf(buffer, sizeof buffer, "%016llx", static_cast<unsigned long long>(h));
  return buffer;
}

json AppendRunHistory(const fs::path& out_dir, const RunRecord& r) {
  const fs::path path = out_dir / "history.json";
  json history = json::array();
  if (std::ifstream in(path); in) {
    try {
      history = json::parse(in);
      if (!history.is_array()) history = json::array();
    } catch (const std::exception&) {
      history = json::array();
    }
  }
  json effects = json::array();
  try {
    for (const model::Effect& e : formats::ReadModelFile(r.model).effects) effects.push_back(model::Describe(e));
  } catch (const std::exception&) {
  }
  json entry = {{"version", static_cast<int>(history.size()) + 1},
                {"stamp", r.stamp},
                {"model", r.model.string()},
                {"hash", FileHash(r.model)},
                {"effects", effects},
                {"mean_agreement_pct_before", Number(r.agreement_before)},
                {"mean_mac_before", Number(r.mac_before)},
                {"mean_agreement_pct_after", Number(r.agreement_after)},
                {"mean_mac_after", Number(r.mac_after)}};
  if (r.rank_one) entry["diagnosis"] = {{"kind", r.rank_one->kind}, {"target", r.rank_one->target}, {"probability", Number(r.rank_one->probability)}};
  history.push_back(entry);
  formats::WriteTextFileAtomically(path, history.dump(2) + "\n");
  return history;
}

}  // namespace ema::app
