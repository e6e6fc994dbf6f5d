// Ground truth shared by the acquisition and frf tests: a 3-DOF spring-mass chain with modal
// damping, mass-normalised real modes from the generalised eigenproblem K phi = w^2 M phi.
#pragma once

#include <Eigen/Dense>
#include <vector>

#include "ema/acquisition/simulator.hpp"

namespace ema::testing {

struct ThreeDof {
  Eigen::Matrix3d m, k;
  std::vector<Dof> dofs{{1, 3}, {2, 3}, {3, 3}};
  acquisition::ModalTruth truth;
  std::vector<double> frequency_hz, damping;
};

/// Masses 1, 1.5, 0.8 kg; springs chosen so the modes lie near 40, 110, 170 Hz; damping 1–1.5 %
/// unless given.
inline ThreeDof MakeThreeDof(std::vector<double> damping = {0.01, 0.012, 0.015}, double stiffness_scale = 1.0) {
  ThreeDof s;
  s.m = Eigen::Vector3d(1.0, 1.5, 0.8).asDiagonal();
  const double k1 = 4.0e5 * stiffness_scale, k2 = 6.0e5 * stiffness_scale, k3 = 5.0e5 * stiffness_scale;
  s.k << k1 + k2, -k2, 0, -k2, k2 + k3, -k3, 0, -k3, k3;
  Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::Matrix3d> eig(s.k, s.m);
  Eigen::Matrix3d phi = eig.eigenvectors();  // mass-normalised: phi^T M phi = I
  for (int r = 0; r < 3; ++r) s.frequency_hz.push_back(std::sqrt(eig.eigenvalues()[r]) / kTwoPi);
  s.damping = damping;
  s.truth = acquisition::ModalTruthFromRealModes(s.dofs, phi, s.frequency_hz, s.damping);
  return s;
}

}  // namespace ema::testing
