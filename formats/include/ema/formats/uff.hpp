// Dataset-level access to Universal File Format (UFF/UNV) files, following shared spec uff.md.
//
// Reading is streaming: uff::Reader walks the file dataset by dataset through a buffered
// binary-mode stream (64-bit offsets), so a multi-GB file is never held in memory; with
// ReadOptions::headers_only the values of 58/58b records are skipped (58b payloads by seeking),
// which is what `ema info` uses. Writing produces 80-column ASCII records with the exact
// Fortran widths of the SDRC descriptions (58b on request).
//
// Supported datasets: 151, 164, 15, 2411, 18, 2420, 82, 55, 58 (ASCII) and 58b (4/8-byte,
// little and big endian). Anything else is kept verbatim as a RawDataset (with a note) so that
// it survives a read/write round trip; 2412 (elements) and 2414 (analysis results) decode from
// their RawDataset on demand (DecodeElements2412, Decode2414AsData55).
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <iosfwd>
#include <memory>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

namespace ema::formats::uff {

/// Dataset 151: file header. Dates/times are opaque strings.
struct Header151 {
  std::string model_name;
  std::string description;
  std::string db_program;
  std::string db_created_date, db_created_time;
  int version1 = 0, version2 = 0, file_type = 0;
  std::string db_saved_date, db_saved_time;
  std::string uff_program;
  std::string uff_written_date, uff_written_time;
};

/// Dataset 164: units. SI value = file value / factor^exponent (spec §4).
struct Units164 {
  int code = 1;  ///< 1 SI ... 9 user defined, 10 mm/N
  std::string description = "SI";
  int temperature_mode = 2;
  double length = 1.0, force = 1.0, temperature = 1.0, temperature_offset = 273.15;
};

/// One node of dataset 15 (single precision) or 2411 (double precision).
struct NodeRecord {
  std::int64_t label = 0;
  int definition_cs = 0;
  int displacement_cs = 0;
  int colour = 0;
  std::array<double, 3> xyz{0.0, 0.0, 0.0};
};

struct Nodes15 {
  std::vector<NodeRecord> nodes;
};
struct Nodes2411 {
  std::vector<NodeRecord> nodes;
};

/// Dataset 18: coordinate systems defined by three points.
struct CoordinateSystem18 {
  int number = 0, type = 0, reference = 0, colour = 0, method = 1;
  std::string name;
  std::array<double, 9> points{};  ///< origin(3), point on +x(3), point in +xz plane(3)
};
struct CoordinateSystems18 {
  std::vector<CoordinateSystem18> systems;
};

/// Dataset 2420: coordinate systems as 4x3 transformation matrices.
struct CoordinateSystem2420 {
  int label = 0, type = 0, colour = 0;
  std::string name;
  std::array<double, 12> matrix{};  ///< rows 1-4, three values each
};
struct CoordinateSystems2420 {
  std::int64_t part_uid = 1;
  std::string part_name = "None";
  std::vector<CoordinateSystem2420> systems;
};

/// Dataset 82: one trace line; node 0 = pen up.
struct TraceLine82 {
  int number = 1;
  int colour = 0;
  std::string id = "NONE";
  std::vector<std::int64_t> nodes;
};

/// Dataset 55: data at nodes (mode shapes).
struct Data55 {
  std::array<std::string, 5> id{"NONE", "NONE", "NONE", "NONE", "NONE"};
  int model_type = 1;
  int analysis_type = 3;        ///< 2 normal mode, 3 complex eigenvalue, ...
  int data_characteristic = 2;  ///< 1 scalar, 2 three-DOF, 3 six-DOF, ...
  int specific_data_type = 12;
  int data_type = 5;            ///< 2 real, 5 complex
  int ndv = 3;                  ///< values per node
  std::vector<std::int64_t> integers;  ///< NINT analysis-specific integers
  std::vector<double> reals;           ///< NRVAL analysis-specific reals
  struct NodeValues {
    std::int64_t node = 0;
    std::vector<double> values;  ///< ndv reals, or 2*ndv (re, im interleaved) when complex
  };
  std::vector<NodeValues> nodes;

  bool IsComplex() const { return data_type == 5 || data_type == 6; }
};

/// Axis description (58 records 8-11).
struct Axis58 {
  int specific_data_type = 0;
  int length_exponent = 0, force_exponent = 0, temperature_exponent = 0;
  std::string label = "NONE";
  std::string units = "NONE";
};

/// Dataset 58 / 58b: one function at a nodal DOF.
struct Function58 {
  std::array<std::string, 5> id{"NONE", "NONE", "NONE", "NONE", "NONE"};
  int function_type = 0;  ///< 1 time, 4 FRF, 6 coherence, ...
  std::int64_t function_id = 0;
  int version = 0;
  std::int64_t load_case = 0;
  std::string response_entity = "NONE";
  std::int64_t response_node = 0;
  int response_direction = 0;
  std::string reference_entity = "NONE";
  std::int64_t reference_node = 0;
  int reference_direction = 0;
  int ordinate_type = 4;  ///< 2 real single, 4 real double, 5 complex single, 6 complex double
  std::int64_t count = 0; ///< N: values (even) or pairs (uneven)
  bool even = true;
  double x_min = 0.0, dx = 0.0, z = 0.0;
  std::array<Axis58, 4> axes;  ///< abscissa, ordinate (numerator), denominator, z
  std::vector<double> x;       ///< abscissa values (uneven spacing only)
  std::vector<double> y;       ///< N reals, or 2N (re, im interleaved) when complex
  bool values_read = true;     ///< false when read with headers_only
  // 58b only
  bool binary = false;
  bool big_endian = false;

  bool IsComplex() const { return ordinate_type == 5 || ordinate_type == 6; }
  bool IsDouble() const { return ordinate_type == 4 || ordinate_type == 6; }
  /// Abscissa of point i (even spacing from record 7, else the stored value).
  double X(std::int64_t i) const { return even ? x_min + static_cast<double>(i) * dx : x[i]; }
};

/// A dataset this library does not decode, kept verbatim (lines without terminators).
struct RawDataset {
  std::vector<std::string> lines;  ///< the dataset-number line and the records
};

using DatasetBody = std::variant<Header151, Units164, Nodes15, Nodes2411, CoordinateSystems18,
                                 CoordinateSystems2420, TraceLine82, Data55, Function58, RawDataset>;

struct Dataset {
  int number = 0;              ///< 58 also for 58b
  std::int64_t line = 0;       ///< 1-based line of the start delimiter
  std::uint64_t offset = 0;    ///< byte offset of the start delimiter
  std::vector<std::string> notes;  ///< recoverable deviations, e.g. "58b: CR LF after payload"
  DatasetBody body;
};

struct ReadOptions {
  bool headers_only = false;    ///< 58/58b: decode records 1-11 only, skip the values
  bool allow_non_finite = false;///< accept NaN/Inf text in data values (default: error)
  /// Accept a 58 whose values end (at its closing delimiter or EOF) before the N of record 7:
  /// keep what was read, reduce N and add a note. Default: error "truncated, got m of M".
  bool allow_truncated = false;
  /// Files at least this big are parsed on two threads (the second half from a dataset boundary
  /// near the middle, verified against the sequential parse; results, notes and errors are exactly
  /// those of a one-thread read). 0 = always one thread. Not used with headers_only.
  std::uint64_t parallel_min_bytes = std::uint64_t{32} << 20;
  /// ...and at most this big: the worker holds the second half in memory until it is handed out,
  /// so a bigger file is streamed on one thread (bounded memory).
  std::uint64_t parallel_max_bytes = std::uint64_t{2} << 30;
};

/// Streaming dataset reader. Throws ema::InputError("file:line: dataset N record R: ...").
class Reader {
 public:
  explicit Reader(const std::filesystem::path& path, ReadOptions options = {});
  ~Reader();
  Reader(const Reader&) = delete;
  Reader& operator=(const Reader&) = delete;

  /// Reads the next dataset; false at end of file.
  bool Next(Dataset* dataset);
  /// Notes about the file outside datasets (junk lines, missing delimiters).
  const std::vector<std::string>& FileNotes() const;
  std::uint64_t FileSize() const;
  std::uint64_t Position() const;
  /// True once the datasets come from the second thread (see ReadOptions::parallel_min_bytes).
  bool ServingParallelHalf() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Dataset 2414 (analysis data, kept as a RawDataset by the reader) as its dataset-55
/// equivalent: normal (2) and complex (3, 7) modes of displacement/velocity/acceleration data at
/// nodes. False for other results (element data, static, stresses ...). Throws InputError naming
/// `where` and the record for malformed records.
bool Decode2414AsData55(const RawDataset& raw, const std::string& where, Data55* out);

/// One element of dataset 2412.
struct Element2412 {
  std::int64_t label = 0;
  int fe_descriptor = 0;  ///< FE descriptor id: 11 rod, 21-24 beams, 41/44 plane, 91/94 thin shell, 111 tetrahedron, ...
  std::int64_t physical_property = 0;  ///< physical property table number
  std::int64_t material_property = 0;  ///< material property table number
  int colour = 0;
  std::vector<std::int64_t> nodes;     ///< node labels, in the element's order
  /// Beam-type elements only (HasBeamRecord2412): orientation node, fore- and aft-end cross
  /// sections; 0 otherwise.
  std::int64_t beam_orientation_node = 0;
  std::int64_t beam_fore_cross_section = 0, beam_aft_cross_section = 0;
};

/// Dataset 2412: the elements of a mesh (test geometry lines and faces, FE meshes).
struct Elements2412 {
  std::vector<Element2412> elements;
};

/// True for the FE descriptors whose elements carry the beam record (rods, beams, pipes: 11,
/// 21, 22, 23, 24, 31, 32).
bool HasBeamRecord2412(int fe_descriptor);

/// Dataset 2412 (kept as a RawDataset by the reader, so it is written back byte for byte) as its
/// elements. `file` and `delimiter_line` (Dataset::line) place messages: InputError
/// "file:line: dataset 2412 element L: ..." for a malformed record or a node list that ends early.
Elements2412 DecodeElements2412(const RawDataset& raw, const std::string& file, std::int64_t delimiter_line);

/// Reads every dataset of a file.
std::vector<Dataset> ReadFile(const std::filesystem::path& path, ReadOptions options = {});

/// True when the first non-blank line of the file is a UFF delimiter "-1".
bool LooksLikeUff(const std::filesystem::path& path);

struct WriteOptions {
  bool binary = false;      ///< write 58 as 58b (little-endian IEEE)
};

/// Writes one dataset (delimiters included) to a binary-mode stream.
void WriteDataset(std::ostream& out, const Dataset& dataset, const WriteOptions& options = {});
void WriteDataset(std::ostream& out, const DatasetBody& body, const WriteOptions& options = {});

/// Writes a whole file atomically.
void WriteFile(const std::filesystem::path& path, const std::vector<Dataset>& datasets,
               const WriteOptions& options = {});

/// Number parsing with the Fortran rules of spec §2.2 (D exponents, letterless exponents,
/// blank = 0, leading '+', NaN/Inf). Returns false when `text` is not a number.
bool ParseReal(std::string_view text, double* value);
bool ParseInteger(std::string_view text, std::int64_t* value);

/// Formats `value` like Fortran 1PEw.d (C "%w.dE"), locale independent; 'D' exponent if asked.
std::string FormatE(double value, int width, int precision, char exponent_letter = 'E');

/// Decodes a DOF hidden in an entity name, as written by tools that leave node and direction
/// 0 in record 6 (spec §12.2): ".1.Z-", ".56.Z", "1+Z", "101:-X". False if it is not one.
bool DecodeEntityName(std::string_view name, std::int64_t* node, int* direction);

/// For a 58 whose response (or reference) node and direction are both 0, takes them from the
/// entity name when DecodeEntityName understands it. Returns true if anything changed.
bool ApplyEntityNameDofs(Function58* f);

/// Dataset number of a body alternative (151, 164, ...; RawDataset gives 0).
int DatasetNumberOf(const DatasetBody& body);

}  // namespace ema::formats::uff
