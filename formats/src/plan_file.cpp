#include "ema/formats/plan_file.hpp"

#include <cctype>
#include <cmath>
#include <stdexcept>
#include <cstdint>
#include <toml++/toml.h>

#include "ema/core/error.hpp"
#include "ema/formats/toml_fields.hpp"

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

}  // namespace ema::formats
