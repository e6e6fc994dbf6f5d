// FRF estimators from averaged auto/cross spectra (spec algorithms.md §1.6–1.9), conversions
// between receptance, mobility and accelerance, and band selection.
#pragma once

#include <Eigen/Core>
#include <string>

#include "ema/core/names.hpp"
#include "ema/core/types.hpp"

namespace ema::frf {

enum class Estimator { kH1, kH2, kHv };
inline constexpr EnumName<Estimator> kEstimatorNames[] = {
    {Estimator::kH1, "H1"}, {Estimator::kH2, "H2"}, {Estimator::kHv, "Hv"}};

/// "H1" / "H2" / "Hv" (case-insensitive) → Estimator; throws std::invalid_argument otherwise.
Estimator ParseEstimator(const std::string& name);
std::string EstimatorName(Estimator e);

/// Averaged SISO spectra of one input/output pair: Gxx = Σ|X|², Gyy = Σ|Y|², Gxy = Σ conj(X) Y
/// (sums; the 1/N factors cancel in every ratio below).
struct CrossSpectra {
  Eigen::ArrayXd gxx, gyy;
  Eigen::ArrayXcd gxy;
  int averages = 0;

  void Resize(Eigen::Index lines);
  /// Adds one impact's spectra.
  void Add(const std::complex<double>* x, const std::complex<double>* y);
};

/// H1 = Gxy/Gxx, H2 = Gyy/Gyx, Hv = Gxy/(Gxx - λmin) (total least squares).
Eigen::ArrayXcd EstimateFrf(const CrossSpectra& s, Estimator estimator);
/// γ² = |Gxy|² / (Gxx Gyy); 0 where a spectrum is zero.
Eigen::ArrayXd Coherence(const CrossSpectra& s);

/// MIMO H1 at one line: H = S_yx S_xx^{-1} (l × m).
Eigen::MatrixXcd MimoH1(const Eigen::MatrixXcd& syx, const Eigen::MatrixXcd& sxx);
/// Multiple coherence of one output with all inputs: s_o S_xx^{-1} s_o^H / S_yy,oo (s_o = row of S_yx).
double MultipleCoherence(const Eigen::RowVectorXcd& s_o, const Eigen::MatrixXcd& sxx, double syy_oo);

/// Power of jω relating a quantity to displacement: 0 displacement, 1 velocity, 2 acceleration.
int DerivativeOrder(Quantity q);
/// Converts an FRF between receptance / mobility / accelerance by (jω)^k. Lines at ω = 0 that
/// need a division become NaN (excluded, spec §1.9).
Eigen::ArrayXcd ConvertFrf(const Eigen::ArrayXcd& h, const Eigen::VectorXd& frequency_hz, Quantity from, Quantity to);
/// Converts every FRF of the set to `to` (units relabelled m, m/s, m/s^2 when they were SI).
void ConvertFrfSet(FrfSet* set, Quantity to);
/// Keeps the lines with lo_hz ≤ f ≤ hi_hz; throws std::invalid_argument when none remain.
FrfSet SelectBand(const FrfSet& set, double lo_hz, double hi_hz);

}  // namespace ema::frf
