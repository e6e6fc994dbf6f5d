// ema simulate MODEL.toml --plan PLAN.toml -o TIME.unv [--setup NAME] [--binary]
//
// A roving hammer test of the model (docs/plan-format.md): per roving set the model is solved
// with that set's sensor masses mounted, its modes become the acquisition simulator's modal
// truth, and the records of every set are written as UFF 58 time data.
#include <cmath>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
#include <set>
#include <toml++/toml.h>

#include "cli.hpp"
#include "ema/acquisition/simulator.hpp"
#include "ema/acquisition/time_simulator.hpp"
#include "ema/core/error.hpp"
#include "ema/formats/io.hpp"
#include "ema/formats/model_file.hpp"
#include "ema/formats/toml_fields.hpp"
#include "ema/model/effects.hpp"
#include "ema/model/law_force.hpp"
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
  bool time_integration = false;  ///< integration = "time": non-linear laws integrated in time
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

/// A model law as the time integrator's restoring force.
class LawRestoringForce : public acquisition::RestoringForce {
 public:
  explicit LawRestoringForce(model::LawForce law) : law_(std::move(law)) {}
  double Force(double c) const override { return law_.Force(c); }
  void Commit(double c) override { law_.Commit(c); }
  void Reset() override { law_.Reset(); }
  double Stiffness() const override { return law_.Stiffness(); }

 private:
  model::LawForce law_;
};

/// integration = "time": per roving set the model (with that set's sensor masses) is assembled
/// at its operating point; every spring whose law is non-linear in time becomes a non-linear
/// element about that point; impacts are integrated in time (docs/plan-format.md).
int SimulateInTime(const model::Model& input, const Plan& plan, const std::string& model_path,
                   const std::string& plan_path, const std::string& out_path, bool binary) {
  const model::Model m = input.effects.empty() ? input : model::ApplyEffects(input);
  std::map<int, const model::TestPoint*> points;
  for (const model::TestPoint& p : m.points) points[p.id] = &p;
  const std::vector<double> levels =
      plan.hammer.force_levels_n.empty() ? std::vector<double>{plan.hammer.force_peak_n} : plan.hammer.force_levels_n;
  const double peak_max = *std::max_element(levels.begin(), levels.end()) * (1.0 + std::abs(plan.hammer.force_spread));
  const double impulse = 2.0 * plan.hammer.pulse_duration_s / 3.14159265358979323846 * peak_max;
  std::vector<acquisition::ImpactFunction> impact;
  std::vector<std::shared_ptr<acquisition::TimeIntegrator>> integrators;
  int nonlinear = 0;
  for (std::size_t s = 0; s < plan.sets.size(); ++s) {
    const RovingSet& set = plan.sets[s];
    model::SolveOptions so;
    so.setup = plan.setup;
    for (const auto& [id, mass] : set.masses) {
      if (!points.count(id)) throw InputError(plan_path, "set '" + set.name + "': mass at unknown point " + std::to_string(id));
      if (mass > 0.0) so.extra_masses.push_back({"sensor@" + std::to_string(id), points[id]->where, mass, 0});
    }
    const model::System sys = model::Assemble(m, so);
    const model::Solution sol = model::Solve(m, so);  // linear modes: the range of each element's motion
    acquisition::TimeDomainTruth truth;
    truth.mass = Eigen::MatrixXd(sys.mass);
    truth.stiffness = Eigen::MatrixXd(sys.stiffness);
    const int n = static_cast<int>(truth.mass.rows());
    if (n > 600)
      throw InputError(model_path, "integration = \"time\" integrates dense matrices: " + std::to_string(n) +
                                       " DOFs is too many (600 at most); use integration = \"modal\"");
    for (std::size_t j = 0; j < sol.modes.modes.size(); ++j) truth.damping_ratios.push_back(sol.modes.modes[j].damping_ratio);
    std::vector<Dof> dofs = plan.hammer.references;
    for (const Dof& d : set.sensors)
      if (std::find(dofs.begin(), dofs.end(), d) == dofs.end()) dofs.push_back(d);
    truth.dofs = dofs;
    truth.observation = Eigen::MatrixXd::Zero(static_cast<int>(dofs.size()), n);
    const Eigen::MatrixXd obs(sys.observation);
    Eigen::MatrixXd ref_shapes(static_cast<int>(plan.hammer.references.size()), sol.full_shapes.cols());
    for (std::size_t i = 0; i < dofs.size(); ++i) {
      const Dof base{dofs[i].node, std::abs(dofs[i].direction)};
      const auto it = std::find(sys.observed_dofs.begin(), sys.observed_dofs.end(), base);
      if (it == sys.observed_dofs.end())
        throw InputError(plan_path, "DOF " + DofName(dofs[i]) + " is not a test point of the model " + model_path);
      const double sign = dofs[i].direction < 0 ? -1.0 : 1.0;
      truth.observation.row(static_cast<int>(i)) = sign * obs.row(static_cast<int>(it - sys.observed_dofs.begin()));
      if (i < plan.hammer.references.size())
        ref_shapes.row(static_cast<int>(i)) = truth.observation.row(static_cast<int>(i)) * sol.full_shapes;
    }
    for (std::size_t k = 0; k < m.springs.size(); ++k) {
      const model::Spring& spring = m.springs[k];
      if (!spring.law.IsNonlinearInTime()) continue;
      Eigen::VectorXd coefficients = Eigen::VectorXd::Zero(n);
      for (const auto& [dof, c] : sys.spring_coefficients[k]) coefficients[dof] -= c;  // compression = -deflection
      // Range of its compression: 3 x the largest modal response to the largest impulse.
      double range = 0.0;
      const Eigen::RowVectorXd modal = coefficients.transpose() * sol.full_shapes;
      for (Eigen::Index r = 0; r < modal.size(); ++r) {
        const double w = kTwoPi * sol.modes.modes[static_cast<std::size_t>(r)].frequency_hz;
        double drive = 0.0;
        for (Eigen::Index i = 0; i < ref_shapes.rows(); ++i) drive = std::max(drive, std::abs(ref_shapes(i, r)));
        if (w > 0.0) range += std::abs(modal[r]) * drive * impulse / w;
      }
      range = std::max(3.0 * range, 1e-9);
      const std::string where = m.Where(spring.line) + ": spring '" + spring.name + "'";
      double override_value = kNaN;
      for (const model::Setup& setup : m.setups)
        if (setup.name == plan.setup) {
          const auto it = setup.operating.find(spring.group);
          if (it != setup.operating.end() && spring.law.IsNonlinear()) override_value = it->second;
        }
      const model::SpringState op = model::LinearizeLaw(spring.law, where, override_value);
      acquisition::NonlinearElement element;
      element.coefficients = coefficients;
      element.force = std::make_shared<LawRestoringForce>(
          model::LawForce(spring.law, op, range, spring.stiffness_factor, where));
      truth.elements.push_back(std::move(element));
    }
    nonlinear = static_cast<int>(truth.elements.size());
    auto integrator = std::make_shared<acquisition::TimeIntegrator>(std::move(truth));
    integrators.push_back(integrator);
    const acquisition::HammerTestPlan& h = plan.hammer;
    impact.push_back([integrator, &h](const Dof& ref, const std::vector<Dof>& responses,
                                      const std::vector<std::pair<double, double>>& pulses) {
      return integrator->Simulate(ref, responses, pulses, h.pulse_duration_s, h.sample_rate_hz, h.samples_per_record,
                                  h.response_quantity, h.oversampling);
    });
    cli::DrawProgress(static_cast<double>(s + 1) / (plan.sets.size() + 1), "assembling set " + set.name);
  }
  std::vector<TimeRecord> records;
  try {
    records = acquisition::SimulateHammerTestWith(impact, plan.hammer);
  } catch (const std::runtime_error& e) {
    throw InputError(plan_path, e.what());
  }
  formats::WriteOptions wo;
  wo.binary = binary;
  formats::WriteTimeRecords(out_path, records, wo);
  cli::DrawProgress(1.0, "done");
  std::cout << "simulated " << records.size() << " records in time (" << nonlinear << " non-linear element(s)): "
            << plan.sets.size() << " roving set(s), " << plan.hammer.references.size() << " reference(s), "
            << plan.hammer.impacts_per_reference << " impacts each at " << levels.size() << " force level(s)\n";
  return 0;
}

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

  if (plan.time_integration) return SimulateInTime(m, plan, model_path, plan_path, out_path, vm["binary"].as<bool>());

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
            << " impacts each" << (plan.hammer.force_levels_n.empty() ? "" : " per force level") << ", "
            << truths.front().poles.size() << " modes\n";
  return 0;
}

}  // namespace ema
