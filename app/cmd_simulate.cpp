// ema simulate MODEL.toml --plan PLAN.toml -o TIME.unv [--setup NAME] [--binary]
//
// A roving hammer test of the model (docs/plan-format.md): per roving set the model is solved
// with that set's sensor masses mounted, its modes become the acquisition simulator's modal
// truth, and the records of every set are written as UFF 58 time data.
#include <cmath>
#include <filesystem>
#include <iostream>
#include <map>
#include <set>
#include <toml++/toml.h>

#include "cli.hpp"
#include "ema/acquisition/simulator.hpp"
#include "ema/core/error.hpp"
#include "ema/formats/io.hpp"
#include "ema/formats/model_file.hpp"
#include "ema/formats/toml_fields.hpp"
#include "ema/model/solve.hpp"

namespace ema {
namespace {

struct RovingSet {
  std::string name;
  std::vector<Dof> sensors;
  std::map<int, double> masses;  // test point id -> sensor mass mounted there
};

struct Plan {
  acquisition::HammerTestPlan hammer;
  std::vector<RovingSet> sets;
  std::string setup;
};

class PlanReader : public formats::TomlFields {
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
    if (!n->is_integer()) throw InputError(At(*n), "key '" + key + "': expected an integer");
    return static_cast<int>(*n->value<int64_t>());
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
               "force_full_scale", "setup"},
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
    h.force_noise = Number(*p, "force_noise", h.force_noise);
    h.response_noise = Number(*p, "response_noise", h.response_noise);
    h.noise_relative_to_peak = Bool(*p, "noise_relative_to_peak", h.noise_relative_to_peak);
    h.trigger_jitter = Bool(*p, "trigger_jitter", h.trigger_jitter);
    h.oversampling = Integer(*p, "oversampling", h.oversampling);
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

int RunSimulate(const std::vector<std::string>& args) {
  namespace po = cli::po;
  po::options_description options("ema simulate options");
  std::string model_path, plan_path, out_path, setup;
  cli::AddHelp(&options);
  options.add_options()                                                                   //
      ("model", po::value(&model_path)->required(), "model file (TOML)")                  //
      ("plan", po::value(&plan_path)->required(), "test plan (TOML, docs/plan-format.md)")  //
      ("output,o", po::value(&out_path)->required(), "time data, UFF 58")                  //
      ("setup", po::value(&setup), "model setup (overrides the plan's setup)")             //
      ("binary", po::bool_switch(), "write UFF 58b (binary)");
  po::positional_options_description positional;
  positional.add("model", 1);
  po::variables_map vm;
  if (!cli::Parse(args, "ema simulate MODEL.toml --plan PLAN.toml -o TIME.unv [--setup NAME] [--binary]", options,
                  positional, &vm))
    return 0;
  cli::RefuseOutputsOverInputs(vm, {"model", "plan"}, {"output"});
  const model::Model m = formats::ReadModelFile(model_path);
  std::error_code exists_ec;
  if (!std::filesystem::exists(plan_path, exists_ec)) throw InputError(plan_path, "plan file not found");
  Plan plan = PlanReader(plan_path).Read();
  if (!setup.empty()) plan.setup = setup;

  std::map<int, const model::TestPoint*> points;
  for (const model::TestPoint& p : m.points) points[p.id] = &p;
  auto require_point = [&](const Dof& d, const std::string& what) {
    if (!points.count(d.node))
      throw InputError(plan_path, what + " " + DofName(d) + ": node " + std::to_string(d.node) +
                                      " is not a [[point]] of the model " + model_path);
  };
  for (const Dof& r : plan.hammer.references) require_point(r, "reference");

  std::vector<acquisition::ModalTruth> truths;
  for (std::size_t s = 0; s < plan.sets.size(); ++s) {
    const RovingSet& set = plan.sets[s];
    model::SolveOptions so;
    so.setup = plan.setup;
    for (const Dof& d : set.sensors) require_point(d, "sensor");
    for (const auto& [id, mass] : set.masses) {
      if (!points.count(id)) throw InputError(plan_path, "set '" + set.name + "': mass at unknown point " + std::to_string(id));
      if (mass > 0.0) so.extra_masses.push_back({"sensor@" + std::to_string(id), points[id]->where, mass, 0});
    }
    const model::Solution sol = model::Solve(m, so);
    if (sol.modes.modes.empty()) throw InputError(model_path, "the model has no elastic modes to simulate");
    // Truth DOFs: references and this set's sensors; shapes from the +X/+Y/+Z test-point DOFs.
    std::vector<Dof> dofs = plan.hammer.references;
    for (const Dof& d : set.sensors)
      if (std::find(dofs.begin(), dofs.end(), d) == dofs.end()) dofs.push_back(d);
    Eigen::MatrixXd phi(static_cast<int>(dofs.size()), static_cast<int>(sol.modes.modes.size()));
    for (std::size_t i = 0; i < dofs.size(); ++i) {
      const Dof base{dofs[i].node, std::abs(dofs[i].direction)};
      const auto it = std::find(sol.modes.dofs.begin(), sol.modes.dofs.end(), base);
      const int row = static_cast<int>(it - sol.modes.dofs.begin());
      const double sign = dofs[i].direction < 0 ? -1.0 : 1.0;
      for (std::size_t j = 0; j < sol.modes.modes.size(); ++j)
        phi(static_cast<int>(i), static_cast<int>(j)) = sign * sol.modes.modes[j].shape[row].real();
    }
    std::vector<double> f, zeta;
    for (const Mode& mode : sol.modes.modes) f.push_back(mode.frequency_hz), zeta.push_back(mode.damping_ratio);
    if (*std::min_element(zeta.begin(), zeta.end()) <= 0.0)
      std::cerr << "ema simulate: warning: undamped modes (set [damping] in the model); records will not decay\n";
    truths.push_back(acquisition::ModalTruthFromRealModes(dofs, phi, f, zeta));
    cli::DrawProgress(static_cast<double>(s + 1) / (plan.sets.size() + 1), "solving set " + set.name);
  }
  const std::vector<TimeRecord> records = acquisition::SimulateHammerTest(truths, plan.hammer);
  formats::WriteOptions wo;
  wo.binary = vm["binary"].as<bool>();
  formats::WriteTimeRecords(out_path, records, wo);
  cli::DrawProgress(1.0, "done");
  std::cout << "simulated " << records.size() << " records: " << plan.sets.size() << " roving set(s), "
            << plan.hammer.references.size() << " reference(s), " << plan.hammer.impacts_per_reference
            << " impacts each, " << truths.front().poles.size() << " modes\n";
  return 0;
}

}  // namespace ema
