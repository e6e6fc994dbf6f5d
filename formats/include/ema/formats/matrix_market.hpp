// Matrix Market (coordinate, real/integer, general/symmetric) reader and writer.
#pragma once

#include <Eigen/SparseCore>
#include <filesystem>

namespace ema::formats {

/// Reads a sparse matrix. A symmetric file is expanded to full storage. Throws InputError naming
/// the file and line on malformed or truncated input.
Eigen::SparseMatrix<double> ReadMatrixMarket(const std::filesystem::path& path);

/// Throws InputError naming the file, and the line and entry (i, j) of the first asymmetric pair,
/// when `matrix` (as read from `path`) is not square or |A_ij - A_ji| exceeds `tolerance` times its
/// largest entry. Used for the [fe] mass and stiffness of a model file.
void RequireSymmetric(const Eigen::SparseMatrix<double>& matrix, const std::filesystem::path& path,
                      double tolerance = 1e-9);

/// Writes a matrix in coordinate real format; `symmetric` stores the lower triangle only.
void WriteMatrixMarket(const std::filesystem::path& path, const Eigen::SparseMatrix<double>& matrix,
                       bool symmetric = true);

}  // namespace ema::formats
