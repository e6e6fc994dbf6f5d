// The test plan of `ema simulate` (TOML, docs/plan-format.md): the hammer test (references,
// sampling, impacts, force, noise), the roving sets of sensors with their masses, and the
// deliberate faults (double hits, overloads).
#pragma once

#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "ema/acquisition/simulator.hpp"
#include "ema/core/types.hpp"

namespace ema::formats {

/// One roving set of sensors.
struct RovingSet {
  std::string name;
  std::vector<Dof> sensors;
  std::map<int, double> masses;  ///< test point id -> sensor mass mounted there, kg
};

struct Plan {
  acquisition::HammerTestPlan hammer;
  std::vector<RovingSet> sets;
  std::string setup;              ///< [plan] setup: the model setup the test is made in
  bool time_integration = false;  ///< integration = "time": non-linear laws integrated in time
};

/// Reads and checks a plan file. InputError ("file:line: what") for bad TOML, an unknown key
/// (with the keys allowed there), a wrong type, a value out of range or a bad DOF.
Plan ReadPlanFile(const std::filesystem::path& path);

/// The TOML text of a plan (docs/plan-format.md) that ReadPlanFile reads back to the same Plan;
/// `comment`: lines written first, each prefixed "# ". Numbers are written in the shortest form
/// that reads back to the same double. The sensors of each set come from `sets` (ReadPlanFile
/// makes hammer.roving_sets from them); a set's masses as ReadPlanFile gives them back: every
/// sensor point holds an entry (a point missing from `masses` is written with 0 kg: no mass), and
/// [plan] sensor_mass is written when all sets share one mass. std::invalid_argument when the plan
/// holds what the format cannot say: a DOF that is not a node 0..999999999 with +-X/Y/Z, a mass at a
/// point id outside 0..999999999, a seed beyond the int range the reader takes, a response quantity other
/// than acceleration/velocity/displacement, a double hit or overload naming no set or reference.
std::string PlanToToml(const Plan& plan, const std::string& comment = "");

/// Writes PlanToToml atomically (WriteTextFileAtomically).
void WritePlanFile(const std::filesystem::path& path, const Plan& plan, const std::string& comment = "");

}  // namespace ema::formats
