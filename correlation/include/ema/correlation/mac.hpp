// Shape correlation measures: MAC, AutoMAC, modal scale factor, COMAC, frequency agreement.
// Formulas: shared spec algorithms.md §5.2–§5.3. All functions are complex-safe; real shapes are
// simply complex vectors with zero imaginary part.
#pragma once

#include <Eigen/Core>
#include <complex>

namespace ema::correlation {

/// Modal assurance criterion |a^H b|^2 / ((a^H a)(b^H b)), in [0, 1]. Invariant to any complex
/// scaling of either vector. Returns 0 when either vector is zero (nothing to correlate).
double Mac(const Eigen::VectorXcd& a, const Eigen::VectorXcd& b);

/// MAC between every column of `a` (rows of the result) and every column of `b` (columns).
/// Both hold one mode per column over the same DOFs (same row count).
/// Throws std::invalid_argument when a and b hold different numbers of DOFs (rows).
Eigen::MatrixXd MacMatrix(const Eigen::MatrixXcd& a, const Eigen::MatrixXcd& b);

/// MAC of a set with itself: symmetric, unit diagonal for non-zero shapes.
Eigen::MatrixXd AutoMac(const Eigen::MatrixXcd& shapes);

/// Modal scale factor that scales `x` onto `a` in the least-squares sense:
/// (x^H a) / (x^H x), so that a ≈ MSF · x. Zero when x is zero.
std::complex<double> ModalScaleFactor(const Eigen::VectorXcd& x, const Eigen::VectorXcd& a);

/// Coordinate MAC per DOF (row) over paired modes (columns of `test` and `model`, column r of
/// one paired with column r of the other). Each test column is first scaled onto its model
/// column with the MSF (COMAC is not scale invariant, §5.2), then
/// COMAC_i = (Σ_r |t_ir conj(m_ir)|)^2 / (Σ_r |t_ir|^2 Σ_r |m_ir|^2). A DOF that is zero in every
/// mode of either set gets 0.
Eigen::VectorXd Comac(const Eigen::MatrixXcd& test, const Eigen::MatrixXcd& model);

/// The reference thesis's "percentage agreement": 100 (1 − |f_model − f_test| / f_model).
double AgreementPct(double model_frequency_hz, double test_frequency_hz);

/// Signed frequency deviation (f_model − f_test) / f_test · 100; positive when the model is stiff.
double FrequencyErrorPct(double model_frequency_hz, double test_frequency_hz);

}  // namespace ema::correlation
