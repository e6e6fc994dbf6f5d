#include "ema/frf/estimators.hpp"

#include <Eigen/Dense>
#include <cmath>
#include <stdexcept>

namespace ema::frf {

using cd = std::complex<double>;

Estimator ParseEstimator(const std::string& name) {
  auto upper = [](std::string text) {
    for (char& c : text) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
    return text;
  };
  for (const EnumName<Estimator>& entry : kEstimatorNames)  // case-insensitive: "h1", "HV"
    if (upper(name) == upper(entry.name)) return entry.value;
  throw std::invalid_argument("unknown estimator '" + name + "' (expected " + NameList(kEstimatorNames) + ")");
}

std::string EstimatorName(Estimator e) { return NameOf(kEstimatorNames, e); }

void CrossSpectra::Resize(Eigen::Index lines) {
  gxx = Eigen::ArrayXd::Zero(lines);
  gyy = Eigen::ArrayXd::Zero(lines);
  gxy = Eigen::ArrayXcd::Zero(lines);
  averages = 0;
}

void CrossSpectra::Add(const cd* x, const cd* y) {
  // Plain real arithmetic: std::complex products go through the C99 Annex G NaN checks.
  const Eigen::Index n = gxx.size();
  const double* xp = reinterpret_cast<const double*>(x);
  const double* yp = reinterpret_cast<const double*>(y);
  double* gxy_p = reinterpret_cast<double*>(gxy.data());
  double* gxx_p = gxx.data();
  double* gyy_p = gyy.data();
  for (Eigen::Index k = 0; k < n; ++k) {
    const double xr = xp[2 * k], xi = xp[2 * k + 1], yr = yp[2 * k], yi = yp[2 * k + 1];
    gxx_p[k] += xr * xr + xi * xi;
    gyy_p[k] += yr * yr + yi * yi;
    gxy_p[2 * k] += xr * yr + xi * yi;      // Re conj(x) y
    gxy_p[2 * k + 1] += xr * yi - xi * yr;  // Im conj(x) y
  }
  ++averages;
}

Eigen::ArrayXcd EstimateFrf(const CrossSpectra& s, Estimator estimator) {
  const Eigen::Index n = s.gxx.size();
  Eigen::ArrayXcd h(n);
  for (Eigen::Index k = 0; k < n; ++k) {
    const double gxx = s.gxx[k], gyy = s.gyy[k];
    const cd gxy = s.gxy[k];
    switch (estimator) {
      case Estimator::kH1: h[k] = gxx > 0.0 ? gxy / gxx : cd(0.0); break;
      case Estimator::kH2: h[k] = std::abs(gxy) > 0.0 ? gyy / std::conj(gxy) : cd(0.0); break;
      case Estimator::kHv: {
        const double lmin = 0.5 * ((gxx + gyy) - std::sqrt((gxx - gyy) * (gxx - gyy) + 4.0 * std::norm(gxy)));
        const double d = gxx - lmin;
        h[k] = d > 0.0 ? gxy / d : cd(0.0);
        break;
      }
    }
  }
  return h;
}

Eigen::ArrayXd Coherence(const CrossSpectra& s) {
  const Eigen::Index n = s.gxx.size();
  Eigen::ArrayXd c(n);
  for (Eigen::Index k = 0; k < n; ++k) {
    const double d = s.gxx[k] * s.gyy[k];
    c[k] = d > 0.0 ? std::min(1.0, std::norm(s.gxy[k]) / d) : 0.0;
  }
  return c;
}

Eigen::MatrixXcd MimoH1(const Eigen::MatrixXcd& syx, const Eigen::MatrixXcd& sxx) {
  // H S_xx = S_yx  →  S_xx^T H^T = S_yx^T (S_xx Hermitian: solve with the adjoint, robust LU).
  return sxx.transpose().partialPivLu().solve(syx.transpose()).transpose();
}

double MultipleCoherence(const Eigen::RowVectorXcd& s_o, const Eigen::MatrixXcd& sxx, double syy_oo) {
  if (!(syy_oo > 0.0)) return 0.0;
  const Eigen::VectorXcd v = sxx.partialPivLu().solve(s_o.adjoint());
  return std::min(1.0, (s_o * v)(0).real() / syy_oo);
}

int DerivativeOrder(Quantity q) {
  switch (q) {
    case Quantity::kDisplacement: return 0;
    case Quantity::kVelocity: return 1;
    default: return 2;
  }
}

Eigen::ArrayXcd ConvertFrf(const Eigen::ArrayXcd& h, const Eigen::VectorXd& frequency_hz, Quantity from, Quantity to) {
  const int k = DerivativeOrder(to) - DerivativeOrder(from);
  if (k == 0) return h;
  Eigen::ArrayXcd out(h.size());
  for (Eigen::Index i = 0; i < h.size(); ++i) {
    const cd jw(0.0, kTwoPi * frequency_hz[i]);
    if (k < 0 && jw == cd(0.0)) {
      out[i] = cd(kNaN, kNaN);
      continue;
    }
    out[i] = h[i] * std::pow(jw, k);
  }
  return out;
}

void ConvertFrfSet(FrfSet* set, Quantity to) {
  if (DerivativeOrder(to) == DerivativeOrder(set->output_quantity)) {
    set->output_quantity = to;
    return;
  }
  for (Eigen::MatrixXcd& h : set->h)
    for (Eigen::Index o = 0; o < h.cols(); ++o) {
      const Eigen::ArrayXcd col = h.col(o).array();
      h.col(o) = ConvertFrf(col, set->frequency_hz, set->output_quantity, to).matrix();
    }
  static const char* kSi[] = {"m", "m/s", "m/s^2"};
  const std::string& u = set->response_unit;
  if (u == "m" || u == "m/s" || u == "m/s^2" || u == "m/s2") set->response_unit = kSi[DerivativeOrder(to)];
  set->output_quantity = to;
}

FrfSet SelectBand(const FrfSet& set, double lo_hz, double hi_hz) {
  std::vector<Eigen::Index> keep;
  for (Eigen::Index i = 0; i < set.frequency_hz.size(); ++i)
    if (set.frequency_hz[i] >= lo_hz && set.frequency_hz[i] <= hi_hz) keep.push_back(i);
  if (keep.empty()) throw std::invalid_argument("the band holds no spectral line");
  FrfSet out = set;
  const auto first = keep.front();
  const auto count = static_cast<Eigen::Index>(keep.size());
  out.frequency_hz = set.frequency_hz.segment(first, count);
  for (size_t r = 0; r < set.h.size(); ++r) out.h[r] = set.h[r].middleRows(first, count);
  for (size_t r = 0; r < set.coherence.size(); ++r) out.coherence[r] = set.coherence[r].middleRows(first, count);
  return out;
}

}  // namespace ema::frf
