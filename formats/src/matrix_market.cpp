// Matrix Market coordinate files (https://math.nist.gov/MatrixMarket/formats.html), written here
// from the format description.
#include "ema/formats/matrix_market.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "ema/core/error.hpp"
#include "ema/formats/atomic_file.hpp"
#include "text_lines.hpp"

namespace ema::formats {

namespace {
constexpr long kMaxDimension = 100000000;  // 1e8 DOFs: far beyond a modal model, well inside int
// Rows and columns beyond the entries: the sparse matrix costs memory and time per column, so a
// 60-byte file declaring 3 x 30000000 with no entry took 0.2 GB and 18 s under ASan
// (fuzz_matrix_market). The matrix of a whole model has an entry on every row (its diagonal), but
// a part of one (model-format.md, [[fe.part]]: a bolted joint, a support spring) lies on a few of
// its DOFs: a size line may declare at most `entries` + 2e6 rows or columns (8 MB of column
// index at most).
constexpr long kDimensionSlack = 2000000;
}  // namespace

Eigen::SparseMatrix<double> ReadMatrixMarket(const std::filesystem::path& path) {
  const std::string file = path.string();
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) throw InputError(file, "is a folder: expected a Matrix Market file");
  std::ifstream in(path);
  if (!in) throw InputError(file, "cannot open Matrix Market file");
  std::string line;
  int line_no = 0;
  if (!ReadTextLine(in, &line, file, 1)) throw InputError(file + ":1", "empty file, expected a %%MatrixMarket header");
  ++line_no;
  std::string lower = line;
  std::transform(lower.begin(), lower.end(), lower.begin(), [](unsigned char c) { return std::tolower(c); });
  std::istringstream header(lower);
  std::string banner, object, format, field, symmetry;
  header >> banner >> object >> format >> field >> symmetry;
  if (banner != "%%matrixmarket" || object != "matrix")
    throw InputError(file + ":1", "expected '%%MatrixMarket matrix coordinate real symmetric|general', found '" + line + "'");
  if (format != "coordinate") throw InputError(file + ":1", "only the 'coordinate' format is supported, found '" + format + "'");
  if (field != "real" && field != "integer" && field != "double")
    throw InputError(file + ":1", "field must be real or integer, found '" + field + "'");
  if (symmetry != "symmetric" && symmetry != "general")
    throw InputError(file + ":1", "symmetry must be symmetric or general, found '" + symmetry + "'");
  const bool symmetric = symmetry == "symmetric";
  long rows = -1, cols = -1, nnz = -1;
  while (ReadTextLine(in, &line, file, line_no + 1)) {
    ++line_no;
    if (line.empty() || line[0] == '%' || line.find_first_not_of(" \t\r") == std::string::npos) continue;
    std::istringstream s(line);
    if (!(s >> rows >> cols >> nnz) || rows < 0 || cols < 0 || nnz < 0)
      throw InputError(file + ":" + std::to_string(line_no), "expected the size line 'rows cols entries'");
    if (rows > kMaxDimension || cols > kMaxDimension || nnz / std::max(1L, rows) > cols)
      throw InputError(file + ":" + std::to_string(line_no),
                       "size line '" + line + "': expected at most " + std::to_string(kMaxDimension) +
                           " rows and columns and at most rows x cols entries");
    if (std::max(rows, cols) > nnz + kDimensionSlack)
      throw InputError(file + ":" + std::to_string(line_no),
                       "size line '" + line + "': " + std::to_string(nnz) + " entries cannot fill " +
                           std::to_string(rows) + " rows and " + std::to_string(cols) +
                           " columns (at most entries + " +
                           std::to_string(kDimensionSlack) + " rows and columns are accepted)");
    break;
  }
  if (rows < 0) throw InputError(file, "missing the size line 'rows cols entries'");
  if (symmetric && rows != cols)
    throw InputError(file + ":" + std::to_string(line_no), "a symmetric matrix must be square, the size line gives " +
                                                               std::to_string(rows) + "x" + std::to_string(cols));
  std::vector<Eigen::Triplet<double>> t;
  // The entries are counted as they come: a size line's count alone never reserves memory.
  t.reserve(static_cast<std::size_t>(std::min(nnz, 1L << 20)));
  long read = 0;
  while (read < nnz && ReadTextLine(in, &line, file, line_no + 1)) {
    ++line_no;
    if (line.empty() || line[0] == '%' || line.find_first_not_of(" \t\r") == std::string::npos) continue;
    long i = 0, j = 0;
    double v = 0.0;
    std::istringstream s(line);
    if (!(s >> i >> j >> v))
      throw InputError(file + ":" + std::to_string(line_no), "expected 'row col value'");
    if (!std::isfinite(v))
      throw InputError(file + ":" + std::to_string(line_no), "entry (" + std::to_string(i) + ", " + std::to_string(j) +
                                                                 ") is not a finite number");
    if (i < 1 || i > rows || j < 1 || j > cols)
      throw InputError(file + ":" + std::to_string(line_no), "index (" + std::to_string(i) + ", " + std::to_string(j) +
                                                                 ") outside the " + std::to_string(rows) + "x" +
                                                                 std::to_string(cols) + " matrix");
    if (symmetric && j > i)
      throw InputError(file + ":" + std::to_string(line_no), "symmetric file holds an upper-triangle entry (" +
                                                                 std::to_string(i) + ", " + std::to_string(j) + ")");
    t.emplace_back(static_cast<int>(i - 1), static_cast<int>(j - 1), v);
    if (symmetric && i != j) t.emplace_back(static_cast<int>(j - 1), static_cast<int>(i - 1), v);
    ++read;
  }
  if (read < nnz)
    throw InputError(file + ":" + std::to_string(line_no), "truncated: expected " + std::to_string(nnz) + " entries, found " +
                                                               std::to_string(read));
  Eigen::SparseMatrix<double> m(static_cast<int>(rows), static_cast<int>(cols));
  m.setFromTriplets(t.begin(), t.end());
  return m;
}

void RequireSymmetric(const Eigen::SparseMatrix<double>& matrix, const std::filesystem::path& path, double tolerance) {
  const std::string file = path.string();
  if (matrix.rows() != matrix.cols())
    throw InputError(file, "expected a square matrix, found " + std::to_string(matrix.rows()) + "x" +
                               std::to_string(matrix.cols()));
  double scale = 0.0;
  for (int c = 0; c < matrix.outerSize(); ++c)
    for (Eigen::SparseMatrix<double>::InnerIterator it(matrix, c); it; ++it) scale = std::max(scale, std::abs(it.value()));
  const Eigen::SparseMatrix<double> transposed = matrix.transpose();
  const Eigen::SparseMatrix<double> difference = matrix - transposed;
  for (int c = 0; c < difference.outerSize(); ++c) {
    for (Eigen::SparseMatrix<double>::InnerIterator it(difference, c); it; ++it) {
      if (!(std::abs(it.value()) > tolerance * scale)) continue;
      // Report the entry of the pair that the file holds, with its line (a second pass over the file).
      long i = it.row() + 1, j = it.col() + 1;
      std::ifstream in(path);
      std::string line;
      int line_no = 0, found = 0;
      bool size_seen = false;
      while (found == 0 && ReadTextLine(in, &line, file, line_no + 1)) {
        ++line_no;
        if (line.empty() || line[0] == '%') continue;
        std::istringstream s(line);
        long a = 0, b = 0;
        if (!(s >> a >> b)) continue;
        if (!size_seen) {
          size_seen = true;
          continue;
        }
        if ((a == i && b == j) || (a == j && b == i)) {
          found = line_no;
          i = a, j = b;
        }
      }
      char text[160];
      std::snprintf(text, sizeof text, "entry (%ld, %ld) = %.6g but (%ld, %ld) = %.6g", i, j,
                    matrix.coeff(static_cast<int>(i - 1), static_cast<int>(j - 1)), j, i,
                    matrix.coeff(static_cast<int>(j - 1), static_cast<int>(i - 1)));
      throw InputError(found > 0 ? file + ":" + std::to_string(found) : file,
                       std::string(text) + ": expected a symmetric matrix (mass and stiffness matrices are symmetric; "
                                           "give the lower triangle with the 'symmetric' header)");
    }
  }
}

void WriteMatrixMarket(const std::filesystem::path& path, const Eigen::SparseMatrix<double>& matrix, bool symmetric) {
  WriteFileAtomically(path, [&](std::ostream& out) {
    long count = 0;
    for (int c = 0; c < matrix.outerSize(); ++c)
      for (Eigen::SparseMatrix<double>::InnerIterator it(matrix, c); it; ++it)
        if (!symmetric || it.row() >= it.col()) ++count;
    out << "%%MatrixMarket matrix coordinate real " << (symmetric ? "symmetric" : "general") << "\n";
    out << matrix.rows() << " " << matrix.cols() << " " << count << "\n";
    out.precision(17);
    for (int c = 0; c < matrix.outerSize(); ++c)
      for (Eigen::SparseMatrix<double>::InnerIterator it(matrix, c); it; ++it)
        if (!symmetric || it.row() >= it.col()) out << it.row() + 1 << " " << it.col() + 1 << " " << it.value() << "\n";
  });
}

}  // namespace ema::formats
