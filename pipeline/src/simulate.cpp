// The simulated roving hammer test (`ema simulate`, a project test's plan = "PLAN.toml"): moved
// here from app/cmd_simulate.cpp so that `ema run` can rehearse a planned test with the same code.
#include <algorithm>
#include <cmath>
#include <map>
#include <memory>

#include "ema/acquisition/simulator.hpp"
#include "ema/acquisition/time_simulator.hpp"
#include "ema/core/error.hpp"
#include "ema/model/effects.hpp"
#include "ema/model/law_force.hpp"
#include "ema/model/solve.hpp"
#include "ema/pipeline/stages.hpp"

namespace ema::pipeline {
namespace {

// Throws naming the plan when `d`'s node is not a [[point]] of the model.
void RequireTestPoint(const model::Model& m, const Dof& d, const std::string& what, const std::string& model_path,
                      const std::string& plan_path) {
  for (const model::TestPoint& p : m.points)
    if (p.id == d.node) return;
  throw InputError(plan_path, what + " " + DofName(d) + ": node " + std::to_string(d.node) +
                                  " is not a [[point]] of the model " + model_path);
}

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
SimulateStage SimulateInTime(const model::Model& input, const formats::Plan& plan, const std::string& model_path,
                             const std::string& plan_path, const ProgressCallback& progress) {
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
    const formats::RovingSet& set = plan.sets[s];
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
    if (progress) progress(static_cast<double>(s + 1) / (plan.sets.size() + 1), "assembling set " + set.name);
  }
  SimulateStage stage;
  try {
    stage.records = acquisition::SimulateHammerTestWith(impact, plan.hammer);
  } catch (const ConvergenceError& e) {
    throw ConvergenceError(plan_path, e.what());
  } catch (const std::runtime_error& e) {
    throw InputError(plan_path, e.what());
  }
  stage.in_time = true;
  stage.nonlinear_elements = nonlinear;
  stage.force_levels = static_cast<int>(levels.size());
  return stage;
}

// integration = "modal" (the default): per roving set the model with that set's sensor masses is
// solved and its modes are the simulator's modal truth.
SimulateStage SimulateModal(const model::Model& m, const formats::Plan& plan, const std::string& model_path,
                            const std::string& plan_path, const ProgressCallback& progress) {
  std::map<int, const model::TestPoint*> points;
  for (const model::TestPoint& p : m.points) points[p.id] = &p;
  bool undamped = false;
  std::vector<acquisition::ModalTruth> truths;
  for (std::size_t s = 0; s < plan.sets.size(); ++s) {
    const formats::RovingSet& set = plan.sets[s];
    model::SolveOptions so;
    so.setup = plan.setup;
    for (const Dof& d : set.sensors) RequireTestPoint(m, d, "sensor", model_path, plan_path);
    for (const auto& [id, mass] : set.masses) {
      if (!points.count(id)) throw InputError(plan_path, "set '" + set.name + "': mass at unknown point " + std::to_string(id));
      if (mass > 0.0) so.extra_masses.push_back({"sensor@" + std::to_string(id), points[id]->where, mass, 0});
    }
    model::Solution sol;
    // FE-sized models: the modes up to four times the Nyquist frequency, by shift-invert, instead of
    // every mode of the mesh (the truncated ones add a quasi-static term of order (f / f_r)² to the
    // records, below 1/16 of the band's top in relative terms; docs/plan-format.md).
    const int model_dofs = 6 * static_cast<int>(m.bodies.size()) + m.fe.Size();
    if (model_dofs > 120) {
      const double cutoff_hz = 2.0 * plan.hammer.sample_rate_hz;
      so.sparse_threshold = 120;
      for (so.max_modes = 40;; so.max_modes *= 2) {
        sol = model::Solve(m, so);
        const bool all = static_cast<int>(sol.modes.modes.size()) < so.max_modes || so.max_modes >= model_dofs / 2;
        if (all || sol.modes.modes.empty() || sol.modes.modes.back().frequency_hz >= cutoff_hz) break;
      }
      while (!sol.modes.modes.empty() && sol.modes.modes.back().frequency_hz > cutoff_hz && sol.modes.modes.size() > 1)
        sol.modes.modes.pop_back();
    } else {
      sol = model::Solve(m, so);
    }
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
    undamped = undamped || *std::min_element(zeta.begin(), zeta.end()) <= 0.0;
    truths.push_back(acquisition::ModalTruthFromRealModes(dofs, phi, f, zeta));
    if (progress) progress(static_cast<double>(s + 1) / (plan.sets.size() + 1), "solving set " + set.name);
  }
  SimulateStage stage;
  stage.records = acquisition::SimulateHammerTest(truths, plan.hammer);
  stage.modes = static_cast<int>(truths.front().poles.size());
  stage.undamped = undamped;
  return stage;
}

}  // namespace

SimulateStage SimulateTest(const model::Model& m, const formats::Plan& plan, const std::string& model_path,
                           const std::string& plan_path, const ProgressCallback& progress) {
  for (const Dof& r : plan.hammer.references) RequireTestPoint(m, r, "reference", model_path, plan_path);

  SimulateStage stage;
  if (plan.time_integration) stage = SimulateInTime(m, plan, model_path, plan_path, progress);
  else stage = SimulateModal(m, plan, model_path, plan_path, progress);
  stage.sets = static_cast<int>(plan.sets.size());
  stage.references = static_cast<int>(plan.hammer.references.size());
  stage.impacts_per_reference = plan.hammer.impacts_per_reference;
  if (!plan.time_integration) stage.force_levels = static_cast<int>(plan.hammer.force_levels_n.size());
  if (progress) progress(1.0, "done");
  return stage;
}


}  // namespace ema::pipeline
