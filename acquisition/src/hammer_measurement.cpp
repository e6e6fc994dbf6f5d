#include "ema/acquisition/hammer_measurement.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <optional>
#include <set>

#include "ema/core/error.hpp"

namespace ema::acquisition {

namespace {

std::string Origin(const RecordSet& set, const TimeRecord& r, size_t index) {
  if (r.origin.empty()) return set.name + ", record " + std::to_string(index + 1);
  if (set.name.empty() || r.origin.find(set.name) != std::string::npos) return r.origin;
  return set.name + ", " + r.origin;  // messages always name the file
}

bool LooksLikeForceUnit(const std::string& unit) {
  std::string u;
  for (char c : unit)
    if (c != ' ') u += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return u == "n" || u == "kn" || u == "lbf" || u == "lb";
}

bool IsForce(const TimeRecord& r) {
  return r.quantity == Quantity::kForce || (r.quantity == Quantity::kUnknown && LooksLikeForceUnit(r.unit));
}

template <typename T>
void AddUnique(std::vector<T>* v, const T& x) {
  if (std::find(v->begin(), v->end(), x) == v->end()) v->push_back(x);
}

struct LocalImpact {
  Dof reference;
  int number = 0;
  int force = -1;               // index into the set's records
  std::vector<int> responses;
};

// Rule 1: group by (reference, impact number). Returns an error message (and record index) on failure.
std::vector<LocalImpact> GroupByLoadCase(const RecordSet& set, std::string* error) {
  std::map<std::pair<Dof, int>, size_t> index;
  std::vector<LocalImpact> out;
  for (size_t i = 0; i < set.records.size(); ++i) {
    const TimeRecord& r = set.records[i];
    const auto key = std::make_pair(r.reference, r.impact);
    auto it = index.find(key);
    if (it == index.end()) {
      it = index.emplace(key, out.size()).first;
      out.push_back({r.reference, r.impact, -1, {}});
    }
    LocalImpact& g = out[it->second];
    if (IsForce(r)) {
      if (g.force >= 0) {
        *error = Origin(set, r, i) + ": a second force record for impact " + std::to_string(r.impact) +
                 " at reference " + DofName(r.reference) + " (first: " + Origin(set, set.records[g.force], g.force) + ")";
        return {};
      }
      g.force = static_cast<int>(i);
    } else {
      g.responses.push_back(static_cast<int>(i));
    }
  }
  for (const LocalImpact& g : out)
    if (g.force < 0) {
      const int i = g.responses.front();
      *error = Origin(set, set.records[i], i) + ": response " + DofName(set.records[i].channel) + " of impact " +
               std::to_string(g.number) + " at reference " + DofName(g.reference) +
               " has no force record (ordinate type 13) for that impact";
      return {};
    }
  return out;
}

// Rule 2: each force record opens an impact; following responses belong to it.
std::optional<std::vector<LocalImpact>> GroupByOrder(const RecordSet& set) {
  std::vector<LocalImpact> out;
  for (size_t i = 0; i < set.records.size(); ++i) {
    const TimeRecord& r = set.records[i];
    if (IsForce(r)) {
      out.push_back({r.reference.node != 0 ? r.reference : r.channel, static_cast<int>(out.size()) + 1,
                     static_cast<int>(i), {}});
    } else {
      if (out.empty()) return std::nullopt;
      out.back().responses.push_back(static_cast<int>(i));
    }
  }
  if (out.empty()) return std::nullopt;
  return out;
}

}  // namespace

HammerMeasurement AssembleHammerMeasurement(std::vector<RecordSet> sets) {
  HammerMeasurement test;
  if (sets.empty()) throw InputError("", "no time records given");
  std::vector<std::vector<Dof>> set_refs(sets.size()), set_outputs(sets.size());
  std::string first_where;
  for (size_t s = 0; s < sets.size(); ++s) {
    RecordSet& set = sets[s];
    if (set.records.empty()) throw InputError(set.name, "no time records (UFF 58, function type 1) found");
    std::string error;
    std::vector<LocalImpact> local = GroupByLoadCase(set, &error);
    if (!error.empty()) {
      auto by_order = GroupByOrder(set);
      if (!by_order) throw InputError(error);
      local = std::move(*by_order);
      test.grouped_by_record_order = true;
      test.notes.push_back(set.name + ": impacts grouped by record order (load case ids do not number impacts)");
    }
    // One sampling for the whole test: one frequency grid.
    for (size_t i = 0; i < set.records.size(); ++i) {
      const TimeRecord& r = set.records[i];
      if (!(r.sample_interval_s > 0.0) || r.samples.size() < 16)
        throw InputError(Origin(set, r, i), "expected a sampled time record (interval > 0, at least 16 samples), found interval " +
                                                std::to_string(r.sample_interval_s) + " s and " +
                                                std::to_string(r.samples.size()) + " samples");
      if (test.samples == 0) {
        test.samples = static_cast<int>(r.samples.size());
        test.sample_interval_s = r.sample_interval_s;
        first_where = Origin(set, r, i);
      } else if (static_cast<int>(r.samples.size()) != test.samples ||
                 std::abs(r.sample_interval_s - test.sample_interval_s) > 1e-9 * test.sample_interval_s) {
        throw InputError(Origin(set, r, i), "expected " + std::to_string(test.samples) + " samples at " +
                                                std::to_string(1.0 / test.sample_interval_s) + " Hz like " + first_where +
                                                ", found " + std::to_string(r.samples.size()) + " samples at " +
                                                std::to_string(1.0 / r.sample_interval_s) + " Hz");
      }
      for (double v : r.samples)
        if (!std::isfinite(v)) throw InputError(Origin(set, r, i), "non-finite sample value");
    }
    const int base = static_cast<int>(test.records.size());
    for (const LocalImpact& g : local) {
      Impact imp;
      imp.set = static_cast<int>(s);
      imp.reference = g.reference;
      imp.number = g.number;
      imp.force = base + g.force;
      for (int i : g.responses) {
        imp.responses.push_back(base + i);
        AddUnique(&set_outputs[s], set.records[i].channel);
      }
      AddUnique(&set_refs[s], g.reference);
      test.impacts.push_back(std::move(imp));
    }
    for (TimeRecord& r : set.records) {
      if (!IsForce(r) && r.quantity == Quantity::kUnknown) {
        r.quantity = Quantity::kAcceleration;
        test.notes.push_back(Origin(set, r, 0) + ": unknown response quantity, assumed acceleration");
      }
      r.origin = Origin(set, r, &r - set.records.data());
      test.records.push_back(std::move(r));
    }
    test.set_names.push_back(set.name);
  }
  for (const Impact& imp : test.impacts) {
    if (imp.responses.empty())
      throw InputError(test.records[imp.force].origin, "force record of impact " + std::to_string(imp.number) +
                                                           " at reference " + DofName(imp.reference) +
                                                           " has no response record");
    const std::vector<double>& force = test.records[imp.force].samples;
    if (std::all_of(force.begin(), force.end(), [](double v) { return v == 0.0; }))
      throw InputError(test.records[imp.force].origin,
                       "force record of impact " + std::to_string(imp.number) + " at reference " + DofName(imp.reference) +
                           " is all zeros: expected a hammer pulse (is the force channel connected, its sensitivity set?)");
    AddUnique(&test.references, imp.reference);
    for (int i : imp.responses) AddUnique(&test.outputs, test.records[i].channel);
  }
  // Sets must share the reference(s), unless the test is a roving hammer split over files.
  auto sorted = [](std::vector<Dof> v) {
    std::sort(v.begin(), v.end());
    return v;
  };
  bool same_sensors = true;
  for (size_t s = 1; s < sets.size(); ++s)
    if (sorted(set_outputs[s]) != sorted(set_outputs[0])) same_sensors = false;
  for (size_t s = 1; s < sets.size(); ++s) {
    if (sorted(set_refs[s]) == sorted(set_refs[0]) || same_sensors) continue;
    std::string refs0, refs;
    for (const Dof& d : set_refs[0]) refs0 += (refs0.empty() ? "" : ", ") + DofName(d);
    for (const Dof& d : set_refs[s]) refs += (refs.empty() ? "" : ", ") + DofName(d);
    const Impact* first = nullptr;
    for (const Impact& imp : test.impacts)
      if (imp.set == static_cast<int>(s)) {
        first = &imp;
        break;
      }
    throw InputError(test.records[first->force].origin,
                     "roving set " + test.set_names[s] + " has reference " + refs + " but " + test.set_names[0] +
                         " has reference " + refs0 + "; the roving sets of one test must share the reference");
  }
  // Roving hammer: several hammer points, identical sensors in every impact, more points than sensors.
  if (test.references.size() > 1) {
    bool fixed = true;
    std::vector<Dof> first;
    for (int i : test.impacts.front().responses) first.push_back(test.records[i].channel);
    first = sorted(first);
    for (const Impact& imp : test.impacts) {
      std::vector<Dof> these;
      for (int i : imp.responses) these.push_back(test.records[i].channel);
      if (sorted(these) != first) fixed = false;
    }
    test.roving_hammer = fixed && test.references.size() > test.outputs.size();
  }
  return test;
}

}  // namespace ema::acquisition
