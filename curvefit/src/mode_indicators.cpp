#include "ema/curvefit/mode_indicators.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <algorithm>

namespace ema::curvefit {

ModeIndicators ComputeModeIndicators(const FitData& data) {
  const int n = data.LineCount(), l = data.OutputCount(), m = data.ReferenceCount();
  ModeIndicators mi;
  mi.frequency_hz = data.frequency_hz;
  const int ns = std::min(l, m);
  mi.cmif.setConstant(n, ns, kNaN);
  mi.mmif.setConstant(n, m, kNaN);
  const std::complex<double> turn = data.frf_type == FrfType::kMobility ? std::complex<double>(0.0, -1.0) : 1.0;
  Eigen::MatrixXcd h(l, m);
  for (int k = 0; k < n; ++k) {
    if (data.line_weight.size() == n && data.line_weight[k] == 0.0) continue;
    for (int o = 0; o < l; ++o)
      for (int i = 0; i < m; ++i) h(o, i) = turn * data.H(k, o, i);
    if (ns > 0) {
      Eigen::JacobiSVD<Eigen::MatrixXcd> svd(h);
      mi.cmif.row(k) = svd.singularValues().head(ns).transpose();
    }
    const Eigen::MatrixXd re = h.real(), im = h.imag();
    const Eigen::MatrixXd a = re.transpose() * re;
    const Eigen::MatrixXd b = a + im.transpose() * im;
    // b is positive definite unless H has a null column (then the line is left NaN).
    Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> ges(a, b);
    if (ges.info() != Eigen::Success) continue;
    Eigen::VectorXd ev = ges.eigenvalues();  // ascending
    for (int i = 0; i < m; ++i) mi.mmif(k, i) = std::clamp(ev[i], 0.0, 1.0);
  }
  return mi;
}

}  // namespace ema::curvefit
