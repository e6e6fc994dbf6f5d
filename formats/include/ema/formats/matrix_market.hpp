// Matrix Market (coordinate, real/integer, general/symmetric) reader and writer.
#pragma once

#include <Eigen/SparseCore>
#include <filesystem>

namespace ema::formats {

/// Reads a sparse matrix. A symmetric file is expanded to full storage. Throws InputError naming
/// the file and line on malformed or truncated input.
Eigen::SparseMatrix<double> ReadMatrixMarket(const std::filesystem::path& path);

/// Writes a matrix in coordinate real format; `symmetric` stores the lower triangle only.
void WriteMatrixMarket(const std::filesystem::path& path, const Eigen::SparseMatrix<double>& matrix,
                       bool symmetric = true);

}  // namespace ema::formats
