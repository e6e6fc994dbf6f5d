#include "ema/correlation/mac.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

namespace ema::correlation {

double Mac(const Eigen::VectorXcd& a, const Eigen::VectorXcd& b) {
  const double aa = a.squaredNorm();
  const double bb = b.squaredNorm();
  if (aa <= 0.0 || bb <= 0.0) return 0.0;
  const double mac = std::norm(a.dot(b)) / (aa * bb);  // Eigen's dot conjugates the first argument
  return std::min(1.0, mac);                           // rounding can push it a hair above 1
}

Eigen::MatrixXd MacMatrix(const Eigen::MatrixXcd& a, const Eigen::MatrixXcd& b) {
  if (a.rows() != b.rows())
    throw std::invalid_argument("mac: a and b must hold the same DOFs (rows): a is " + std::to_string(a.rows()) + "×" +
                                std::to_string(a.cols()) + ", b is " + std::to_string(b.rows()) + "×" +
                                std::to_string(b.cols()));
  Eigen::MatrixXd mac(a.cols(), b.cols());
  for (Eigen::Index i = 0; i < a.cols(); ++i)
    for (Eigen::Index j = 0; j < b.cols(); ++j) mac(i, j) = Mac(a.col(i), b.col(j));
  return mac;
}

Eigen::MatrixXd AutoMac(const Eigen::MatrixXcd& shapes) {
  Eigen::MatrixXd mac(shapes.cols(), shapes.cols());
  for (Eigen::Index i = 0; i < shapes.cols(); ++i) {
    mac(i, i) = shapes.col(i).squaredNorm() > 0.0 ? 1.0 : 0.0;
    for (Eigen::Index j = i + 1; j < shapes.cols(); ++j) mac(i, j) = mac(j, i) = Mac(shapes.col(i), shapes.col(j));
  }
  return mac;
}

std::complex<double> ModalScaleFactor(const Eigen::VectorXcd& x, const Eigen::VectorXcd& a) {
  const double xx = x.squaredNorm();
  if (xx <= 0.0) return {0.0, 0.0};
  return x.dot(a) / xx;
}

Eigen::VectorXd Comac(const Eigen::MatrixXcd& test, const Eigen::MatrixXcd& model) {
  const Eigen::Index n = test.rows();
  Eigen::VectorXd cross = Eigen::VectorXd::Zero(n);
  Eigen::VectorXd tt = Eigen::VectorXd::Zero(n);
  Eigen::VectorXd mm = Eigen::VectorXd::Zero(n);
  for (Eigen::Index r = 0; r < test.cols() && r < model.cols(); ++r) {
    const Eigen::VectorXcd t = ModalScaleFactor(test.col(r), model.col(r)) * test.col(r);
    for (Eigen::Index i = 0; i < n; ++i) {
      cross(i) += std::abs(t(i) * std::conj(model(i, r)));
      tt(i) += std::norm(t(i));
      mm(i) += std::norm(model(i, r));
    }
  }
  Eigen::VectorXd comac(n);
  for (Eigen::Index i = 0; i < n; ++i)
    comac(i) = (tt(i) > 0.0 && mm(i) > 0.0) ? cross(i) * cross(i) / (tt(i) * mm(i)) : 0.0;
  return comac;
}

double AgreementPct(double model_frequency_hz, double test_frequency_hz) {
  return 100.0 * (1.0 - std::abs(model_frequency_hz - test_frequency_hz) / model_frequency_hz);
}

double FrequencyErrorPct(double model_frequency_hz, double test_frequency_hz) {
  return 100.0 * (model_frequency_hz - test_frequency_hz) / test_frequency_hz;
}

}  // namespace ema::correlation
