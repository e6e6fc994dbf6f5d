// Helpers shared by the frf tests: a simulated 3-DOF hammer test turned into a HammerMeasurement.
#pragma once

#include <vector>

#include "acquisition/three_dof.hpp"
#include "ema/acquisition/hammer_measurement.hpp"
#include "ema/acquisition/simulator.hpp"
#include "ema/frf/hammer_frf.hpp"

namespace ema::testing {

/// Roving-accelerometer test on the 3-DOF chain: hammer at 1+Z, all three DOFs measured,
/// fs 4096 Hz, 2 s records (T ≥ 6 τ of the slowest mode), T_c 1 ms, 5 impacts.
inline acquisition::HammerTestPlan ThreeDofPlan() {
  acquisition::HammerTestPlan plan;
  plan.sample_rate_hz = 4096.0;
  plan.samples_per_record = 8192;
  plan.pulse_duration_s = 1e-3;
  plan.references = {{1, 3}};
  plan.roving_sets = {{{1, 3}, {2, 3}, {3, 3}}};
  plan.impacts_per_reference = 5;
  plan.seed = 7;
  return plan;
}

inline std::vector<acquisition::RecordSet> ToRecordSets(std::vector<acquisition::SimulatedSet> sets) {
  std::vector<acquisition::RecordSet> out;
  for (size_t s = 0; s < sets.size(); ++s) out.push_back({"set" + std::to_string(s + 1) + ".unv", std::move(sets[s].records)});
  return out;
}

inline frf::FrfResult SimulateAndEstimate(const acquisition::ModalTruth& truth, const acquisition::HammerTestPlan& plan,
                                          const frf::FrfOptions& options = {}) {
  return frf::EstimateFrfs(acquisition::AssembleHammerMeasurement(ToRecordSets(acquisition::SimulateHammerTestSets({truth}, plan))),
                           options);
}

}  // namespace ema::testing
