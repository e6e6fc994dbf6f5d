// What a UFF (or CSV time-data) file holds, from a header-only scan: `ema info`.
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <set>
#include <string>
#include <utility>
#include <vector>

namespace ema::formats {

struct FileSummary {
  std::string file;
  std::uint64_t bytes = 0;
  std::string format;                        ///< "uff" or "csv"
  std::map<int, int> datasets;               ///< dataset number -> count (58b counted as 58)
  int binary58 = 0;                          ///< how many of the 58 are 58b
  std::map<int, int> function_types;         ///< 58 function type -> count
  int records = 0;                           ///< 58 records (or CSV channel records)
  std::set<std::int64_t> geometry_nodes;     ///< labels of 15/2411 nodes
  std::set<std::pair<std::int64_t, int>> response_dofs;   ///< 58 (node, direction)
  std::set<std::pair<std::int64_t, int>> reference_dofs;  ///< 58 reference (node, direction)
  std::set<std::int64_t> shape_nodes;        ///< nodes with 55 values
  int modes = 0;                             ///< 55 datasets with analysis type 2, 3 or 7
  std::int64_t elements = 0;                 ///< 2412 elements
  std::map<int, std::int64_t> element_descriptors;  ///< 2412 FE descriptor id -> element count
  struct Abscissa {
    double min = 0.0, max = 0.0;
    std::int64_t points_min = 0, points_max = 0;
    std::set<std::string> units;             ///< abscissa units labels
    std::set<std::string> ordinate_units;    ///< ordinate (numerator/denominator) units labels
  };
  std::map<int, Abscissa> abscissa;          ///< per 58 function type
  std::vector<std::string> units;            ///< 164 descriptions ("SI (code 1)")
  std::vector<std::string> notes;            ///< reader notes (deduplicated, counted)
};

/// Header-only scan (58/58b values are skipped, 58b payloads by seeking). Throws InputError.
FileSummary SummarizeFile(const std::filesystem::path& path);

/// Human-readable multi-line text of a summary.
std::string SummaryText(const FileSummary& summary);

/// "+X", "-RZ", "S" for a UFF direction code (same text as ema::DirectionName).
std::string DirectionText(int code);

/// Name of a 58 function type ("time response", "frequency response function", ...).
std::string FunctionTypeName(int type);

}  // namespace ema::formats
