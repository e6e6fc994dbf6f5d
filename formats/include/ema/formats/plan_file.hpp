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

}  // namespace ema::formats
