// A hammer measurement = reference DOFs × roving sets × impacts, assembled from the time records
// of a hammer test.
//
// Grouping rule (docs/frf.md):
//  1. Within one file (one roving set), records are grouped by (reference DOF, impact number)
//     — in UFF 58 the load case id numbers the impact, the reference node/direction name the
//     hammer point. Each group needs exactly one force record (quantity 13).
//  2. Files from tools that number impacts differently (every record its own load case, or all
//     zero) fail rule 1; they are then grouped by record order: every force record opens an
//     impact and the response records that follow it belong to it.
//  3. Several files are several roving sets of one test. They must share the reference DOF(s);
//     a file with a different reference is an error, except when every file holds the same fixed
//     sensors (a roving-hammer test split over files).
//  4. Roving hammer: more than one hammer point, every impact with the same response DOFs and
//     more hammer points than sensors. FrfSet keeps the physical orientation (references =
//     hammer points, outputs = fixed sensors) and sets roving_hammer so the fit uses reciprocity.
#pragma once

#include <string>
#include <vector>

#include "ema/core/types.hpp"

namespace ema::acquisition {

/// The records of one acquisition file (one roving set); name is used in messages.
struct RecordSet {
  std::string name;
  std::vector<TimeRecord> records;
};

/// One impact: a force record and the response records acquired with it.
struct Impact {
  int set = 0;                ///< index into HammerMeasurement::set_names
  Dof reference;              ///< hammer DOF
  int number = 0;             ///< impact number as read (load case id), or its order in the file (rule 2)
  int force = -1;             ///< index into HammerMeasurement::records
  std::vector<int> responses; ///< indices into HammerMeasurement::records
};

struct HammerMeasurement {
  std::vector<std::string> set_names;
  std::vector<TimeRecord> records;
  std::vector<Impact> impacts;
  std::vector<Dof> references;   ///< distinct hammer DOFs in order of appearance
  std::vector<Dof> outputs;      ///< distinct response DOFs in order of appearance
  double sample_interval_s = 0.0;
  int samples = 0;
  bool roving_hammer = false;
  bool grouped_by_record_order = false;  ///< rule 2 was needed for at least one file
  std::vector<std::string> notes;        ///< non-fatal remarks (grouping rule used, assumed quantities)
};

/// Assembles the test. Throws InputError naming the file, the record and the reason for: a
/// response with no force record for its impact, two force records for one impact, records of
/// different sample intervals or lengths, no records, a set with a different reference.
HammerMeasurement AssembleHammerMeasurement(std::vector<RecordSet> sets);

}  // namespace ema::acquisition
