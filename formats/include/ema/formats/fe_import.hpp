// FE matrices as FE codes write them, turned into the [fe] + [[fe.part]] model of
// model-format.md ("FE models built from parts"), sparse throughout (`ema fe-import`,
// docs/fe-parts.md).
//
// Readers:
//  * CalculiX `*FREQUENCY, SOLVER=MATRIXSTORAGE`: `job.sti` (stiffness) and `job.mas` (mass), one
//    entry a line `row column value`, 1-based, the upper triangle only (row <= column), every entry
//    of the sparsity pattern (numerical zeros too); `job.dof`, one line per matrix row,
//    `node.direction` (17.3 = node 17, z). DOFs fixed by *BOUNDARY are left out.
//  * Abaqus `*MATRIX OUTPUT, FORMAT=MATRIX INPUT` (`job_STIF1.mtx`, `job_MASS1.mtx`, and
//    `*MATRIX GENERATE, ELSET=` for one element set): one entry a line
//    `row node, row dof, column node, column dof, value` (the *MATRIX INPUT data lines), a
//    symmetric matrix as its lower triangle, upper triangle or both (then both must agree). The
//    DOF map is the set of (node, dof) labels, ordered by node, then dof.
//
// Parts, by the difference of two assemblies (docs/fe-parts.md): K_p = (K_nominal − K_p,run) /
// (1 − s_p) for a run with part p's modulus × s_p, or a part's own matrix (Abaqus ELSET=);
// K_rest = K_nominal − Σ K_p. Every matrix is kept as the lower triangle (row >= column) of the
// symmetric matrix; no dense matrix of the model's size is ever made. Checks, each an InputError
// naming the file and the line, row or DOF: symmetry (a lower-triangle entry in a CalculiX file;
// the two triangles of an Abaqus file disagree), the DOF map of every run is the nominal one, a
// part lies on the nominal pattern and is not empty, each part is positive semi-definite (sparse
// Cholesky of K_p + τI on its own DOFs: CHOLMOD when built with it, else Eigen's LDLᵀ), the
// parts do not overlap (K_rest has no negative diagonal: two parts holding the same elements'
// stiffness), and, given the deck's element sets, each part lies on its own elements' DOF pairs
// and K_rest on the other elements' (the checks of samples/bolted-frame/make_sample.py before
// this import, with its tolerances).
#pragma once

#include <Eigen/SparseCore>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "ema/core/progress.hpp"

namespace ema::formats {

/// One row of an FE matrix: a node and a direction (1..6 = ux uy uz rx ry rz).
struct FeDof {
  long node = 0;
  int direction = 0;
  bool operator==(const FeDof&) const = default;
  auto operator<=>(const FeDof&) const = default;
};

/// "17.3" (the CalculiX spelling, used in messages).
std::string FeDofText(const FeDof& dof);

/// A CalculiX `.dof` file: one `node.direction` a line. InputError (file:line) on a malformed
/// line, a direction outside 1..6 or a DOF listed twice.
std::vector<FeDof> ReadCalculixDofs(const std::filesystem::path& path);

/// A CalculiX `.sti` / `.mas` file of a model of `size` DOFs, as the lower triangle of the
/// symmetric matrix (explicit zeros kept: they are the assembly's pattern). InputError (file:line)
/// on a malformed line, an index outside 1..size, an entry below the diagonal (row > column: the
/// file is not ccx's upper triangle) or an entry given twice.
Eigen::SparseMatrix<double> ReadCalculixMatrix(const std::filesystem::path& path, Eigen::Index size);

/// An Abaqus matrix file (`FORMAT=MATRIX INPUT`) with its own DOF map (the labels it holds,
/// ascending).
struct AbaqusMatrix {
  std::vector<FeDof> dofs;
  Eigen::SparseMatrix<double> lower;  ///< lower triangle, rows in `dofs` order
};

/// Reads an Abaqus matrix. With `dofs`, the rows are those DOFs (a label not among them is an
/// InputError naming the line) and the result's `dofs` is `*dofs`. InputError (file:line) on a
/// malformed line, a DOF outside 1..6, an entry given twice, or the two triangles disagreeing
/// (relative `symmetry_tolerance` of the largest entry).
AbaqusMatrix ReadAbaqusMatrix(const std::filesystem::path& path, const std::vector<FeDof>* dofs = nullptr,
                              double symmetry_tolerance = 1e-9);

/// The elements of an input deck (CalculiX or Abaqus `.inp`) and its element sets: each part's
/// elements, for the check that a part lies on its own elements' DOFs.
struct FeElementSets {
  std::vector<std::vector<long>> nodes;  ///< per element, its nodes (sorted)
  /// Set name (upper case, as ccx and Abaqus compare them) → indices into `nodes`.
  std::vector<std::pair<std::string, std::vector<int>>> sets;
  std::filesystem::path file;            ///< the deck (messages)
  /// The elements of set `name` (any case); nullptr when the deck has no such set.
  const std::vector<int>* Find(const std::string& name) const;
};

/// Reads `*ELEMENT` blocks (with their `ELSET=`) and `*ELSET` blocks (lists of elements or sets,
/// `GENERATE`) of a deck; every other keyword is skipped. InputError (file:line) on a malformed
/// data line, an element defined twice or an `*INCLUDE` (give the deck with its includes inlined).
FeElementSets ReadInpElementSets(const std::filesystem::path& path);

/// The files of one FE run.
struct FeRun {
  enum class Code { kCalculix, kAbaqus };
  Code code = Code::kCalculix;
  std::filesystem::path stiffness;  ///< job.sti | job_STIF1.mtx
  std::filesystem::path mass;       ///< job.mas | job_MASS1.mtx ("" = none)
  std::filesystem::path dofs;       ///< job.dof (CalculiX only)
};

/// The run named on a command line: `X.mtx` is an Abaqus stiffness file (its mass: the same name
/// with `_STIF` → `_MASS`, when that file exists); anything else is a CalculiX job name (`job`,
/// `job.sti` or `job.inp` → job.sti, job.mas, job.dof).
FeRun FeRunNamed(const std::string& text);

/// A part: by difference (`run` with the part's modulus × `scale`) or its own matrix (`direct`:
/// `run.stiffness` is the part's stiffness, Abaqus `*MATRIX GENERATE, ELSET=`).
struct FePartInput {
  std::string name;
  FeRun run;
  double scale = 0.5;
  bool direct = false;
};

/// Tolerances of the import. Defaults as the bolted-frame sample's script had them.
struct FeImportOptions {
  /// With the deck's element sets: a part's entries off its own elements' DOF pairs are round-off
  /// up to part_tolerance × max |K_nominal| (zeroed), an error above. Without: a part keeps every
  /// nonzero of the difference (off the part both runs print the same numbers: exact zeros).
  double part_tolerance = 1e-12;
  /// K_rest's entries where only parts have elements (with the deck: off the other elements' DOF
  /// pairs; without: on the parts' pattern) are round-off up to rest_tolerance × max |K_nominal|
  /// (zeroed); with the deck, an error above (a part's run did not change all of its elements).
  double rest_tolerance = 1e-11;
  /// A part is positive semi-definite when K_p + τI factorises with positive pivots, τ =
  /// psd_tolerance × its largest diagonal entry (then λ_min > −τ).
  double psd_tolerance = 1e-9;
  /// The two triangles of a matrix written in full must agree to this, relative to its largest entry.
  double symmetry_tolerance = 1e-9;
  bool IsValid(std::string* why) const;
};

/// One imported part.
struct FeImportedPart {
  std::string name;
  Eigen::SparseMatrix<double> stiffness;  ///< lower triangle, model size
  std::filesystem::path source;           ///< the file it came from (messages)
  Eigen::Index dof_count = 0;             ///< rows with entries
  double largest_dropped = 0.0;           ///< off its elements, relative to max |K_nominal|
  double scale = 0.5;
  bool direct = false;
};

/// The imported model: [fe] mass and stiffness (K_rest), the parts, the DOF map.
struct FeImport {
  std::vector<FeDof> dofs;
  Eigen::SparseMatrix<double> mass;       ///< lower triangle (empty: no mass file)
  Eigen::SparseMatrix<double> rest;       ///< K_nominal − Σ parts, lower triangle
  std::vector<FeImportedPart> parts;
  double max_stiffness = 0.0;             ///< max |K_nominal|
  double rest_largest_dropped = 0.0;      ///< relative to max |K_nominal|
};

/// Reads the nominal run and the parts' runs and makes the parts (see the file comment), with
/// every check. `elements` (optional): the deck's element sets, a part's set named as the part;
/// the elements in no part's set are the rest's. `progress` gets the share of the work done.
FeImport ImportFeParts(const FeRun& nominal, const std::vector<FePartInput>& parts,
                       const FeImportOptions& options = {}, const ProgressCallback& progress = {},
                       const FeElementSets* elements = nullptr);

/// How the import is written.
struct FeImportWriteOptions {
  std::string group;                  ///< the parts' group ("" = none)
  std::optional<double> uncertainty;  ///< the parts' prior (relative 1σ)
  std::string nodes;                  ///< [fe] nodes, as written into the TOML ("" = none)
  std::string comment;                ///< first comment lines of the TOML (without '#')
};

/// The files WriteFeImport writes beside `toml`: M.mtx (when there is mass), K_rest.mtx,
/// K_<part>.mtx, dofs.csv.
std::vector<std::filesystem::path> FeImportOutputs(const FeImport& imported, const std::filesystem::path& toml);

/// Writes `toml` ([fe] + one [[fe.part]] per part) and the files of FeImportOutputs, each atomically.
void WriteFeImport(const FeImport& imported, const std::filesystem::path& toml, const FeImportWriteOptions& options);

}  // namespace ema::formats
