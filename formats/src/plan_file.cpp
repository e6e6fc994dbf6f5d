#include "ema/formats/plan_file.hpp"

#include <cctype>
#include <cmath>
#include <cstring>
#include <limits>
#include <set>
#include <stdexcept>
#include <cstdint>
#include <toml++/toml.h>

#include "ema/core/error.hpp"
#include "ema/formats/atomic_file.hpp"
#include "ema/formats/toml_fields.hpp"
#include "toml_text.hpp"

namespace ema::formats {

namespace {

class PlanReader : public TomlFields {
 public:
  explicit PlanReader(const std::string& path) : TomlFields(path) {}

  double Number(const toml::table& t, const std::string& key, double fallback) const {
    const toml::node* n = t.get(key);
    if (!n) return fallback;
    if (!n->is_number()) throw InputError(At(*n), "key '" + key + "': expected a number");
    return *n->value<double>();
  }
  int Integer(const toml::table& t, const std::string& key, int fallback) const {
    const toml::node* n = t.get(key);
    if (!n) return fallback;
    const auto v = IntValue(*n);
    if (!v) throw InputError(At(*n), "key '" + key + "': expected an integer (within ±2147483647)");
    return *v;
  }
  bool Bool(const toml::table& t, const std::string& key, bool fallback) const {
    const toml::node* n = t.get(key);
    if (!n) return fallback;
    if (!n->is_boolean()) throw InputError(At(*n), "key '" + key + "': expected true or false");
    return *n->value<bool>();
  }
  /// "101+Z", "101:-Y", "101 X".
  Dof ParseDof(const toml::node& n, const std::string& key) const {
    const auto text = n.value<std::string>();
    if (!text || !n.is_string()) throw InputError(At(n), "key '" + key + "': expected a DOF string such as \"101+Z\"");
    std::size_t i = 0;
    while (i < text->size() && std::isdigit(static_cast<unsigned char>((*text)[i]))) ++i;
    std::string rest = text->substr(i);
    while (!rest.empty() && (rest.front() == ':' || rest.front() == ' ')) rest.erase(rest.begin());
    const int dir = ParseDirection(rest);
    if (i == 0 || i > 9 || dir == 0 || std::abs(dir) > 3)  // node ids up to 9 digits (int)
      throw InputError(At(n), "key '" + key + "': '" + *text + "' is not a DOF such as \"101+Z\" (node, +X/-X/+Y/-Y/+Z/-Z)");
    return {std::stoi(text->substr(0, i)), dir};
  }
  const toml::table& TableOf(const toml::node& n, const std::string& what) const {
    const toml::table* t = n.as_table();
    if (!t) throw InputError(At(n), what + " must be a table ([[" + what + "]])");
    return *t;
  }
  std::vector<Dof> DofList(const toml::node& n, const std::string& key) const {
    const toml::array* a = n.as_array();
    if (!a || a->empty()) throw InputError(At(n), "key '" + key + "': expected a non-empty array of DOF strings");
    std::vector<Dof> out;
    for (const toml::node& e : *a) out.push_back(ParseDof(e, key));
    return out;
  }

  Plan Read() const {
    toml::table root;
    try {
      root = toml::parse_file(file_);
    } catch (const toml::parse_error& e) {
      throw InputError(file_ + ":" + std::to_string(e.source().begin.line), std::string(e.description()));
    }
    CheckKeys(root, {"plan", "set", "double_hit", "overload"}, "the plan file");
    const toml::table* p = root["plan"].as_table();
    if (!p) throw InputError(file_, "missing [plan] table (references, sample_rate_hz, samples, ...)");
    CheckKeys(*p,
              {"references", "sample_rate_hz", "samples", "record_length_s", "pre_trigger", "impacts", "force_peak_n",
               "force_spread", "pulse_duration_s", "force_noise", "response_noise", "noise_relative_to_peak",
               "response", "sensor_mass", "seed", "trigger_jitter", "oversampling", "response_full_scale",
               "force_full_scale", "setup", "force_levels_n", "integration"},
              "[plan]");
    Plan plan;
    auto& h = plan.hammer;
    if (!p->get("references")) throw InputError(At(*p), "[plan]: missing key 'references' (hammer DOFs, e.g. [\"101+Z\"])");
    h.references = DofList(*p->get("references"), "references");
    h.sample_rate_hz = Number(*p, "sample_rate_hz", h.sample_rate_hz);
    if (!(h.sample_rate_hz > 0)) throw InputError(At(*p), "[plan]: sample_rate_hz must be > 0");
    h.samples_per_record = Integer(*p, "samples", h.samples_per_record);
    if (p->get("record_length_s"))
      h.samples_per_record = static_cast<int>(std::lround(Number(*p, "record_length_s", 0.0) * h.sample_rate_hz));
    if (h.samples_per_record < 16) throw InputError(At(*p), "[plan]: record must hold at least 16 samples");
    h.pre_trigger_fraction = Number(*p, "pre_trigger", h.pre_trigger_fraction);
    h.impacts_per_reference = Integer(*p, "impacts", h.impacts_per_reference);
    if (h.impacts_per_reference < 1) throw InputError(At(*p), "[plan]: impacts must be >= 1");
    h.force_peak_n = Number(*p, "force_peak_n", h.force_peak_n);
    h.force_spread = Number(*p, "force_spread", h.force_spread);
    h.pulse_duration_s = Number(*p, "pulse_duration_s", h.pulse_duration_s);
    if (!(h.pulse_duration_s > 0.0))
      throw InputError(At(p->get("pulse_duration_s") ? *p->get("pulse_duration_s") : *p), "[plan]: pulse_duration_s must be > 0");
    h.force_noise = Number(*p, "force_noise", h.force_noise);
    h.response_noise = Number(*p, "response_noise", h.response_noise);
    h.noise_relative_to_peak = Bool(*p, "noise_relative_to_peak", h.noise_relative_to_peak);
    h.trigger_jitter = Bool(*p, "trigger_jitter", h.trigger_jitter);
    h.oversampling = Integer(*p, "oversampling", h.oversampling);
    if (h.oversampling < 1) throw InputError(At(p->get("oversampling") ? *p->get("oversampling") : *p), "[plan]: oversampling must be >= 1");
    // The simulator refines its grid for short pulses up to a limit; past it the pulse would be
    // lost between two fine samples (all-zero force records), so the plan is refused here.
    try {
      acquisition::EffectiveOversampling(h.pulse_duration_s, h.sample_rate_hz, h.oversampling);
    } catch (const std::invalid_argument& e) {
      throw InputError(At(p->get("pulse_duration_s") ? *p->get("pulse_duration_s") : *p), std::string("[plan]: pulse_duration_s: ") + e.what());
    }
    h.seed = static_cast<std::uint64_t>(Integer(*p, "seed", 1));
    h.response_full_scale = Number(*p, "response_full_scale", kNaN);
    h.force_full_scale = Number(*p, "force_full_scale", kNaN);
    if (const toml::node* r = p->get("response")) {
      const std::string q = r->value<std::string>().value_or("");
      if (q == "acceleration") h.response_quantity = Quantity::kAcceleration;
      else if (q == "velocity") h.response_quantity = Quantity::kVelocity;
      else if (q == "displacement") h.response_quantity = Quantity::kDisplacement;
      else throw InputError(At(*r), "[plan]: response must be acceleration, velocity or displacement");
    }
    if (const toml::node* s = p->get("setup")) plan.setup = s->value<std::string>().value_or("");
    if (const toml::node* levels = p->get("force_levels_n")) {
      const toml::array* a = levels->as_array();
      if (!a || a->empty()) throw InputError(At(*levels), "[plan]: force_levels_n must be a non-empty array of forces in N");
      for (const toml::node& e : *a) {
        if (!e.is_number() || !(*e.value<double>() > 0.0))
          throw InputError(At(e), "[plan]: force_levels_n: expected forces > 0 in N");
        h.force_levels_n.push_back(*e.value<double>());
      }
    }
    if (const toml::node* integ = p->get("integration")) {
      const std::string mode = integ->value<std::string>().value_or("");
      if (mode == "time") plan.time_integration = true;
      else if (mode != "modal")
        throw InputError(At(*integ), "[plan]: integration must be \"modal\" (linearised, exact modal superposition) or "
                                     "\"time\" (non-linear laws integrated in time)");
    }
    const double default_mass = Number(*p, "sensor_mass", 0.0);

    if (root.get("set") && !root["set"].as_array()) throw InputError(At(*root.get("set")), "'set' must be [[set]] tables");
    if (root.get("double_hit") && !root["double_hit"].as_array())
      throw InputError(At(*root.get("double_hit")), "'double_hit' must be [[double_hit]] tables");
    if (root.get("overload") && !root["overload"].as_array())
      throw InputError(At(*root.get("overload")), "'overload' must be [[overload]] tables");
    const toml::array* sets = root["set"].as_array();
    if (!sets || sets->empty()) throw InputError(file_, "the plan needs at least one [[set]] of sensors");
    for (const toml::node& node : *sets) {
      const toml::table& t = TableOf(node, "set");
      CheckKeys(t, {"name", "sensors", "sensor_mass", "masses"}, "[[set]]");
      RovingSet set;
      set.name = t["name"].value<std::string>().value_or("set " + std::to_string(plan.sets.size() + 1));
      if (!t.get("sensors")) throw InputError(At(t), "[[set]]: missing key 'sensors'");
      set.sensors = DofList(*t.get("sensors"), "sensors");
      const double mass = Number(t, "sensor_mass", default_mass);
      if (!(mass >= 0.0)) throw InputError(At(t), "[[set]]: sensor_mass must be >= 0");
      // One sensor body per point: a triaxial accelerometer (or a uniaxial one) loads its point once.
      for (const Dof& d : set.sensors) set.masses[d.node] = mass;
      if (const toml::table* m = t["masses"].as_table())
        for (const auto& [k, v] : *m) {
          const std::string key(k.str());
          if (!v.is_number()) throw InputError(At(v), "[[set]] masses: expected a number for point " + key);
          const bool digits = !key.empty() && key.size() <= 9 && key.find_first_not_of("0123456789") == std::string::npos;
          if (!digits) throw InputError(At(v), "[[set]] masses: key '" + key + "' is not a test point id");
          set.masses[std::stoi(key)] = *v.value<double>();
        }
      plan.sets.push_back(std::move(set));
    }
    h.roving_sets.clear();
    for (const RovingSet& s : plan.sets) h.roving_sets.push_back(s.sensors);

    auto reference_index = [&](const toml::table& t, const std::string& ctx) {
      if (!t.get("reference")) return 0;
      const Dof ref = ParseDof(*t.get("reference"), "reference");
      for (std::size_t i = 0; i < h.references.size(); ++i)
        if (h.references[i] == ref) return static_cast<int>(i);
      throw InputError(At(t), ctx + ": reference " + DofName(ref) + " is not one of [plan] references");
    };
    auto set_index = [&](const toml::table& t, const std::string& ctx) {
      const int s = Integer(t, "set", 1);
      if (s < 1 || s > static_cast<int>(plan.sets.size()))
        throw InputError(At(t), ctx + ": set must be 1.." + std::to_string(plan.sets.size()));
      return s - 1;
    };
    if (const toml::array* hits = root["double_hit"].as_array())
      for (const toml::node& node : *hits) {
        const toml::table& t = TableOf(node, "double_hit");
        CheckKeys(t, {"set", "reference", "impact", "delay_s", "ratio"}, "[[double_hit]]");
        acquisition::DoubleHit d;
        d.set = set_index(t, "[[double_hit]]");
        d.reference = reference_index(t, "[[double_hit]]");
        d.impact = Integer(t, "impact", 1);
        d.delay_s = Number(t, "delay_s", d.delay_s);
        d.ratio = Number(t, "ratio", d.ratio);
        h.double_hits.push_back(d);
      }
    if (const toml::array* overloads = root["overload"].as_array())
      for (const toml::node& node : *overloads) {
        const toml::table& t = TableOf(node, "overload");
        CheckKeys(t, {"set", "reference", "impact", "channel", "full_scale"}, "[[overload]]");
        acquisition::Clipping c;
        c.set = set_index(t, "[[overload]]");
        c.reference = reference_index(t, "[[overload]]");
        c.impact = Integer(t, "impact", 1);
        const toml::node* ch = t.get("channel");
        if (!ch) throw InputError(At(t), "[[overload]]: missing key 'channel' (\"force\" or a sensor DOF)");
        if (ch->value<std::string>().value_or("") == "force") {
          c.force = true;
          c.channel = h.references[static_cast<std::size_t>(c.reference)];
        } else {
          c.channel = ParseDof(*ch, "channel");
        }
        c.full_scale = Number(t, "full_scale", 0.0);
        if (!(c.full_scale > 0)) throw InputError(At(t), "[[overload]]: full_scale must be > 0");
        h.clipping.push_back(c);
      }
    return plan;
  }
};

}  // namespace

Plan ReadPlanFile(const std::filesystem::path& path) { return PlanReader(path.string()).Read(); }

namespace {

// (Helper names unique in the formats target: it is a unity build.)

// Bit-for-bit the same value as ReadPlanFile gives back (0.0 and -0.0 differ; NaN equals NaN).
bool PlanSameNumber(double a, double b) {
  if (std::isnan(a) || std::isnan(b)) return std::isnan(a) && std::isnan(b);
  return a == b && std::signbit(a) == std::signbit(b);
}

std::string PlanDof(const Dof& d, const std::string& what) {
  if (d.node < 0 || d.node > 999999999 || d.direction == 0 || std::abs(d.direction) > 3)
    throw std::invalid_argument("PlanToToml: " + what + " " + DofName(d) +
                                " is not a plan DOF (node 0..999999999, direction +-X/Y/Z)");
  return DofName(d);
}

std::string PlanDofArray(const std::vector<Dof>& dofs, const std::string& what) {
  std::string s = "[";
  for (std::size_t i = 0; i < dofs.size(); ++i) s += (i ? ", " : "") + TomlString(PlanDof(dofs[i], what));
  return s + "]";
}

// The mass ReadPlanFile gives every sensor point of a set when its table says nothing more: the
// mass at the first sensor point (0 when that is absent, negative or NaN, which sensor_mass
// cannot say; the `masses` table then carries every point).
double PlanBaseMass(const RovingSet& set) {
  if (set.sensors.empty()) return 0.0;
  const auto it = set.masses.find(set.sensors.front().node);
  if (it == set.masses.end() || !(it->second >= 0.0)) return 0.0;
  return it->second;
}

}  // namespace

std::string PlanToToml(const Plan& plan, const std::string& comment) {
  const acquisition::HammerTestPlan& h = plan.hammer;
  std::string s;
  if (!comment.empty()) {
    std::size_t start = 0;
    while (start <= comment.size()) {
      std::size_t end = comment.find('\n', start);
      if (end == std::string::npos) end = comment.size();
      std::string line = comment.substr(start, end - start);
      if (!(end == comment.size() && line.empty() && start > 0)) {  // no empty line for a trailing newline
        std::string clean;
        for (const char c : line) {
          const auto u = static_cast<unsigned char>(c);
          if (c == '\r') continue;
          clean += (u < 0x20 && c != '\t') || u == 0x7f ? ' ' : c;  // TOML comments hold no control bytes
        }
        s += clean.empty() ? "#\n" : "# " + clean + "\n";
      }
      start = end + 1;
    }
    s += "\n";
  }

  // Masses: [plan] sensor_mass when every set has the same base mass, else one per set.
  std::set<std::uint64_t> bases;
  for (const RovingSet& set : plan.sets) {
    const double b = PlanBaseMass(set);
    std::uint64_t bits = 0;
    static_assert(sizeof bits == sizeof b);
    std::memcpy(&bits, &b, sizeof b);
    bases.insert(bits);
  }
  const bool shared_mass = bases.size() == 1;
  const double plan_mass = shared_mass ? PlanBaseMass(plan.sets.front()) : 0.0;

  s += "[plan]\n";
  if (!plan.setup.empty()) s += "setup = " + TomlString(plan.setup) + "\n";
  s += "references = " + PlanDofArray(h.references, "reference") + "\n";
  s += "sample_rate_hz = " + TomlFloat(h.sample_rate_hz) + "\n";
  s += "samples = " + std::to_string(h.samples_per_record) + "\n";
  s += "pre_trigger = " + TomlFloat(h.pre_trigger_fraction) + "\n";
  s += "impacts = " + std::to_string(h.impacts_per_reference) + "\n";
  s += "force_peak_n = " + TomlFloat(h.force_peak_n) + "\n";
  s += "force_spread = " + TomlFloat(h.force_spread) + "\n";
  s += "pulse_duration_s = " + TomlFloat(h.pulse_duration_s) + "\n";
  s += "force_noise = " + TomlFloat(h.force_noise) + "\n";
  s += "response_noise = " + TomlFloat(h.response_noise) + "\n";
  s += std::string("noise_relative_to_peak = ") + (h.noise_relative_to_peak ? "true" : "false") + "\n";
  switch (h.response_quantity) {
    case Quantity::kAcceleration: s += "response = \"acceleration\"\n"; break;
    case Quantity::kVelocity: s += "response = \"velocity\"\n"; break;
    case Quantity::kDisplacement: s += "response = \"displacement\"\n"; break;
    default:
      throw std::invalid_argument("PlanToToml: response quantity " + std::to_string(static_cast<int>(h.response_quantity)) +
                                  " is not acceleration, velocity or displacement");
  }
  if (shared_mass && !PlanSameNumber(plan_mass, 0.0)) s += "sensor_mass = " + TomlFloat(plan_mass) + "\n";
  // ReadPlanFile reads the seed as an int and converts it: a negative one stands for 2^64 - |seed|.
  const auto seed = static_cast<std::int64_t>(h.seed);
  if (seed < std::numeric_limits<int>::min() || seed > std::numeric_limits<int>::max())
    throw std::invalid_argument("PlanToToml: seed " + std::to_string(h.seed) + " is beyond the plan file's int range");
  s += "seed = " + std::to_string(seed) + "\n";
  s += std::string("trigger_jitter = ") + (h.trigger_jitter ? "true" : "false") + "\n";
  s += "oversampling = " + std::to_string(h.oversampling) + "\n";
  if (!std::isnan(h.response_full_scale)) s += "response_full_scale = " + TomlFloat(h.response_full_scale) + "\n";
  if (!std::isnan(h.force_full_scale)) s += "force_full_scale = " + TomlFloat(h.force_full_scale) + "\n";
  if (!h.force_levels_n.empty()) {
    s += "force_levels_n = [";
    for (std::size_t i = 0; i < h.force_levels_n.size(); ++i) s += (i ? ", " : "") + TomlFloat(h.force_levels_n[i]);
    s += "]\n";
  }
  if (plan.time_integration) s += "integration = \"time\"\n";

  for (const RovingSet& set : plan.sets) {
    s += "\n[[set]]\nname = " + TomlString(set.name) + "\n";
    s += "sensors = " + PlanDofArray(set.sensors, "sensor") + "\n";
    const double base = shared_mass ? plan_mass : PlanBaseMass(set);
    if (!shared_mass) s += "sensor_mass = " + TomlFloat(base) + "\n";
    std::map<int, double> table;  // what the base mass of the set does not give
    std::set<int> sensor_points;
    for (const Dof& d : set.sensors) sensor_points.insert(d.node);
    for (const int p : sensor_points)
      if (!set.masses.count(p) && !PlanSameNumber(base, 0.0)) table[p] = 0.0;
    for (const auto& [p, m] : set.masses) {
      if (p < 0 || p > 999999999)
        throw std::invalid_argument("PlanToToml: set '" + set.name + "': a mass at point " + std::to_string(p) +
                                    ", which is no test point id");
      if (!sensor_points.count(p) || !PlanSameNumber(m, base)) table[p] = m;
    }
    if (!table.empty()) {
      s += "masses = { ";
      bool first = true;
      for (const auto& [p, m] : table) {
        s += (first ? "" : ", ") + std::to_string(p) + " = " + TomlFloat(m);
        first = false;
      }
      s += " }\n";
    }
  }

  auto set_number = [&](int set, const std::string& what) {
    if (set < 0 || set >= static_cast<int>(plan.sets.size()))
      throw std::invalid_argument("PlanToToml: " + what + " in set index " + std::to_string(set) + ", the plan has " +
                                  std::to_string(plan.sets.size()) + " sets");
    return std::to_string(set + 1);
  };
  auto reference = [&](int r, const std::string& what) {
    if (r < 0 || r >= static_cast<int>(h.references.size()))
      throw std::invalid_argument("PlanToToml: " + what + " at reference index " + std::to_string(r) + ", the plan has " +
                                  std::to_string(h.references.size()) + " references");
    return TomlString(PlanDof(h.references[static_cast<std::size_t>(r)], "reference"));
  };
  for (const acquisition::DoubleHit& d : h.double_hits) {
    s += "\n[[double_hit]]\nset = " + set_number(d.set, "a double hit") + "\n";
    s += "reference = " + reference(d.reference, "a double hit") + "\n";
    s += "impact = " + std::to_string(d.impact) + "\n";
    s += "delay_s = " + TomlFloat(d.delay_s) + "\n";
    s += "ratio = " + TomlFloat(d.ratio) + "\n";
  }
  for (const acquisition::Clipping& c : h.clipping) {
    s += "\n[[overload]]\nset = " + set_number(c.set, "an overload") + "\n";
    s += "reference = " + reference(c.reference, "an overload") + "\n";
    s += "impact = " + std::to_string(c.impact) + "\n";
    s += "channel = " + (c.force ? std::string("\"force\"") : TomlString(PlanDof(c.channel, "overload channel"))) + "\n";
    s += "full_scale = " + TomlFloat(c.full_scale) + "\n";
  }
  return s;
}

void WritePlanFile(const std::filesystem::path& path, const Plan& plan, const std::string& comment) {
  WriteTextFileAtomically(path, PlanToToml(plan, comment));
}

}  // namespace ema::formats
