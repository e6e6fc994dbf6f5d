// File-level entry points that turn files into the core vocabulary types and back.
// (UFF dataset-level access lives in ema/formats/uff.hpp.)
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "ema/core/types.hpp"

namespace ema::formats {

struct WriteOptions {
  bool binary = false;  ///< write 58b (binary) where the dataset allows it; ASCII otherwise
};

/// Hammer-test time data: UFF 58/58b function-type-1 records, MATLAB .mat, or CSV (docs/formats.md), chosen by
/// content (a CSV file does not start with a UFF delimiter). Throws InputError naming file/line.
std::vector<TimeRecord> ReadTimeRecords(const std::filesystem::path& path);

/// MATLAB .mat hammer-test time data (v5/v7/v7.3, through matio), docs/formats.md "MATLAB .mat
/// time data": `fs` [Hz] (or `dt` [s]), `force` (samples × impacts), `response` (samples ×
/// channels [× impacts]), `reference` ('1+Z'), `channels` ({'1+Z', '2+Z'}), optional `quantity`,
/// `force_unit`, `response_unit`. ReadTimeRecords dispatches here for .mat files.
std::vector<TimeRecord> ReadMatTimeRecords(const std::filesystem::path& path);

/// True when the file starts with a MATLAB 5.0/7.3 MAT-file header.
bool LooksLikeMat(const std::filesystem::path& path);

/// Writes time records as UFF 58 (function type 1) in the convention `ema frf` reads.
void WriteTimeRecords(const std::filesystem::path& path, const std::vector<TimeRecord>& records,
                      const WriteOptions& options = {});

/// FRFs (UFF 58 function type 4) and, when present, coherences (type 6) of one test; a folder
/// or a file that is not UFF is read as an FRF table (ReadFrfTable).
FrfSet ReadFrfSet(const std::filesystem::path& path);

/// Writes FRFs (type 4) and coherences (type 6) with correct units and data-type codes.
void WriteFrfSet(const std::filesystem::path& path, const FrfSet& frfs, const WriteOptions& options = {});

/// What the UFF 58 file WriteFrfSet(path, frfs, options) writes holds, as ReadFrfSet returns
/// it (numbers at the precision of their fields), computed without a file: a pipeline hands on
/// exactly what a later command reading the file gets (formats/src/stored_view.cpp).
FrfSet StoredFrfSet(const FrfSet& frfs, const WriteOptions& options = {});

/// Mode shapes (UFF 55) with geometry from datasets 15/2411 when the file holds them; or, for a
/// file that starts with '{', MODES.json in `ema fit --json`'s layout (model-format.md, added turn
/// 3): `shape` lists exactly the measured DOFs (the same in every mode; `value` [re, im] or a real
/// number), `frequency_std_hz` the measured 1σ of the frequency; no geometry.
ModeSet ReadModeSet(const std::filesystem::path& path);

/// The same from MODES.json's text itself (what a Python dict in that layout holds): `origin`
/// names it in messages, as a file's name does, and is the set's source.
ModeSet ReadModeSetJsonText(const std::string& text, const std::string& origin);

/// Writes 151 header, 15 geometry (when known) and one 55 complex-mode dataset per mode.
void WriteModeSet(const std::filesystem::path& path, const ModeSet& modes, const WriteOptions& options = {});

/// What the UFF 55 file WriteModeSet(path, modes) writes holds, as ReadModeSet(path) returns it
/// (shape values and poles to six significant digits, fields UFF has no place for dropped;
/// source = the file name), computed without a file.
ModeSet StoredModeSet(const ModeSet& modes, const std::filesystem::path& path);

/// CSV hammer-test time data (docs/formats.md): header names carry role, node and direction
/// (`time`, `force:1:+Z`, `acc:101:+X`, optional `[unit]` suffix, optional `impact` column).
/// ReadTimeRecords dispatches here for files that are not UFF.
std::vector<TimeRecord> ReadCsvTimeRecords(const std::filesystem::path& path);

/// Writes time records as CSV in the same convention (one `impact` column, records of one
/// impact must share sample interval and length).
void WriteCsvTimeRecords(const std::filesystem::path& path, const std::vector<TimeRecord>& records);

/// One complex value per line, written as `(re+imj)` (Python repr), `re+imj`, `re` or `nan`;
/// blank lines and lines starting with '#' are skipped; NaN allowed.
Eigen::VectorXcd ReadComplexColumnText(const std::filesystem::path& path);

/// The index file of a folder of FRF columns (see ReadFrfTable).
inline constexpr const char* kFrfIndexFileName = "frfs.csv";

/// Measured FRFs as text tables (docs/formats.md, "FRF tables"), any DOFs:
/// - a file: a table whose header names the frequency column and each FRF as
///   RESPONSE/REFERENCE (`frequency_hz, 1+X/1+X, 1+X/2+X`), complex cells `(re+imj)`, or
///   `re:1+X/2+X` and `im:1+X/2+X` column pairs; `# quantity: acceleration|velocity|displacement`;
/// - a folder: its `frfs.csv` index (`file, response, reference` and a
///   `# frequency_hz: START:STEP` line) names one complex-column file per FRF; a folder of the
///   published pyuff beam data (`meas_point_{1,2,3}.txt`, no index) reads with that data's DOFs.
/// FRFs not in the table are NaN (not measured). Throws InputError naming the file and line.
FrfSet ReadFrfTable(const std::filesystem::path& path);

}  // namespace ema::formats
