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

// Global position of an anchor (body point, body centre, FE node); false when unknown.
bool Place(const model::Model& m, const model::Anchor& a, const model::Anchor* fallback, Eigen::Vector3d* p) {
  if (a.IsNode()) {
    auto it = m.fe.node_positions.find(a.node);
    if (it == m.fe.node_positions.end()) return false;
    *p = it->second;
    return true;
  }
  if (a.has_at) {
    *p = a.at;
    return true;
  }
  if (fallback && fallback->has_at) {
    *p = fallback->at;
    return true;
  }
  if (const model::Body* b = m.FindBody(a.body)) {
    *p = b->centre;
    return true;
  }
  return false;
}

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
  if (r.diagnosis.contains("candidates") && r.diagnosis["candidates"].is_array() && !r.diagnosis["candidates"].empty()) {
    const json& c = r.diagnosis["candidates"][0];
    entry["diagnosis"] = {{"kind", c.value("kind", std::string())},
                          {"target", c.value("target", std::string())},
                          {"probability", c.contains("probability") ? c["probability"] : json(nullptr)}};
  }
  history.push_back(entry);
  formats::WriteTextFileAtomically(path, history.dump(2) + "\n");
  return history;
}

json DiagnosedPlaces(const fs::path& model_file, const json& diagnosis) {
  try {
    return DiagnosedPlaces(formats::ReadModelFile(model_file), diagnosis);
  } catch (const std::exception&) {
    return json::array();
  }
}

json DiagnosedPlaces(const model::Model& m, const json& diagnosis) {
  json out = json::array();
  if (!diagnosis.contains("candidates") || !diagnosis["candidates"].is_array() || diagnosis["candidates"].empty())
    return out;
  const json& first = diagnosis["candidates"][0];
  if (!first.contains("effects") || !first["effects"].is_array()) return out;
  for (const json& e : first["effects"]) {
    const std::string kind = e.value("kind", std::string()), target = e.value("target", std::string());
    const model::EffectKindInfo* info = model::FindEffectKind(kind);
    if (!info) continue;
    json points = json::array();
    auto add = [&](const Eigen::Vector3d& p) { points.push_back({p.x(), p.y(), p.z()}); };
    Eigen::Vector3d p;
    if (info->target == model::EffectTarget::kSprings) {
      for (int i : model::TargetSprings(m, target)) {
        const model::Spring& s = m.springs[i];
        if (Place(m, s.a, nullptr, &p)) add(p);
        if (!s.b.IsGround() && Place(m, s.b, &s.a, &p)) add(p);
      }
    } else if (info->target == model::EffectTarget::kPoints) {
      std::vector<int> ids;
      if (target.rfind("points:", 0) == 0) {
        std::stringstream list(target.substr(7));
        std::string item;
        while (std::getline(list, item, ',')) ids.push_back(std::atoi(item.c_str()));
      }
      for (const model::TestPoint& tp : m.points)
        if ((ids.empty() || std::find(ids.begin(), ids.end(), tp.id) != ids.end()) && Place(m, tp.where, nullptr, &p))
          add(p);
    } else if (const model::Body* b = m.FindBody(target)) {
      add(b->centre);
    }
    const auto slash = target.find('/');
    const std::string label = slash == std::string::npos ? target : target.substr(slash + 1);
    out.push_back({{"target", target}, {"kind", kind}, {"label", label}, {"points", points}});
  }
  return out;
}

}  // namespace ema::app
