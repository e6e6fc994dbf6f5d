#pragma once
// Truths the model cannot express, on the two-body stack of the diagnosis benchmark
// (tests/diagnose/data/benchmark-stack2.toml), and the test a hammer test of them gives: shared by
// the model-error tests of the diagnosis (tests/diagnose/model_error_test.cpp) and of its first
// screen (tests/app/cmd_diagnose_test.cpp).

#include <cmath>
#include <complex>
#include <filesystem>
#include <random>

#include "ema/formats/model_file.hpp"
#include "ema/model/solve.hpp"

namespace ema::test {

inline model::Model Stack() {
  return formats::ReadModelFile(std::filesystem::path(EMA_SOURCE_DIR) / "tests/diagnose/data/benchmark-stack2.toml");
}

/// Each spring's stiffness times e^(scatter·N(0,1)), drawn with `seed`.
inline model::Model Scattered(const model::Model& nominal, double scatter, unsigned seed) {
  model::Model truth = nominal;
  std::mt19937 rng(seed);
  std::normal_distribution<double> g;
  for (auto& s : truth.springs) s.stiffness_factor *= std::exp(scatter * g(rng));
  return truth;
}

/// Every body `factor` times heavier, mass and inertia alike: a spread non-structural mass.
inline void SpreadMass(model::Model* truth, double factor) {
  for (auto& b : truth->bodies) {
    b.mass *= factor;
    b.inertia *= factor;
    b.products *= factor;
  }
}

/// The truth's modes with 0.1 % frequency and 1 % shape noise (what the benchmark's hammer tests
/// give), fixed seed.
inline ModeSet Measured(const model::Model& truth, unsigned seed) {
  ModeSet modes = model::Solve(truth, {}).modes;
  std::mt19937 rng(seed + 1000);
  std::normal_distribution<double> g;
  for (Mode& mode : modes.modes) {
    mode.frequency_hz *= 1.0 + 1e-3 * g(rng);
    const double rms = std::sqrt(mode.shape.squaredNorm() / mode.shape.size());
    for (Eigen::Index i = 0; i < mode.shape.size(); ++i) mode.shape(i) += 1e-2 * rms * std::complex<double>(g(rng), g(rng));
    mode.pole = FrequencyAndDampingToPole(mode.frequency_hz, mode.damping_ratio);
  }
  modes.source = "scattered stack";
  return modes;
}

}  // namespace ema::test
