// ML refinement of the modal model (issue 18): accuracy on a known model with noise, Monte Carlo
// checks of bias and of the Fisher-information sigma, the --refine none path and the options.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

#include "curvefit/synthetic.hpp"
#include "ema/curvefit/fit.hpp"

namespace ema::curvefit {
namespace {

using test::MakeFrfSet;
using test::MakeTruth;
using test::Truth;

// Issue 18's set: 7 modes 110-440 Hz, zeta 0.1-5 %, the 3 %-damped mode at 440 Hz within 15 % of
// the upper band edge (500 Hz: 12 % below it).
Truth SevenModes(int n_dofs) {
  return MakeTruth({110.0, 160.0, 205.0, 262.0, 318.0, 371.0, 440.0}, {0.001, 0.005, 0.01, 0.02, 0.05, 0.015, 0.03},
                   n_dofs);
}

int Nearest(const ModeSet& modes, double f_hz) {
  int best = -1;
  for (int k = 0; k < static_cast<int>(modes.modes.size()); ++k)
    if (std::abs(modes.modes[k].frequency_hz - f_hz) < 0.02 * f_hz &&
        (best < 0 || std::abs(modes.modes[k].frequency_hz - f_hz) < std::abs(modes.modes[best].frequency_hz - f_hz)))
      best = k;
  return best;
}

double ComplexMac(const Eigen::VectorXcd& a, const Eigen::VectorXcd& b) {
  return std::norm(a.dot(b)) / (a.squaredNorm() * b.squaredNorm());
}

// 16 outputs × 3 references × 4000 lines (0.125 Hz to 500 Hz): the line count, a third of
// its 144 FRFs to keep the suite fast (bench_polymax runs the full set).
FrfSet SevenModeSet(double noise, unsigned seed) { return MakeFrfSet(SevenModes(16), {2, 7, 12}, 500.0, 0.125, noise, seed); }

TEST(MlRefine, SevenModesOnePercentNoise) {
  const Truth truth = SevenModes(16);
  const FitResult fit = Fit(SevenModeSet(0.01, 21), FitOptions{});
  ASSERT_TRUE(fit.refine.IsSolutionUsable()) << fit.refine.BriefReport();
  EXPECT_EQ(fit.refine.noise_source, NoiseSource::kResidual);  // synthetic set: no coherence
  ASSERT_EQ(fit.modes.modes.size(), truth.modes.size());
  for (const auto& t : truth.modes) {
    const int k = Nearest(fit.modes, t.f_hz);
    ASSERT_GE(k, 0) << t.f_hz;
    const Mode& m = fit.modes.modes[k];
    // Issue 18 acceptance at 1 % noise: f within 0.05 %, zeta within 2 % (relative). PolyMAX alone
    // misses the 440 Hz mode by 0.07 % here; the ML estimate is within a few sigma (sigma ~ 5e-6 rel).
    EXPECT_NEAR(m.frequency_hz / t.f_hz, 1.0, 5e-4) << t.f_hz;
    EXPECT_NEAR(m.damping_ratio / t.zeta, 1.0, 0.02) << t.f_hz;
    // The sigma is finite, positive and a few times the truth error at most (not a free pass).
    ASSERT_TRUE(std::isfinite(m.frequency_std_hz) && m.frequency_std_hz > 0.0);
    ASSERT_TRUE(std::isfinite(m.damping_ratio_std) && m.damping_ratio_std > 0.0);
    EXPECT_LT(std::abs(m.frequency_hz - t.f_hz), 5.0 * m.frequency_std_hz) << t.f_hz;
    EXPECT_LT(std::abs(m.damping_ratio - t.zeta), 5.0 * m.damping_ratio_std) << t.f_hz;
    EXPECT_GE(ComplexMac(m.shape, t.shape.cast<std::complex<double>>()), 0.995);
    EXPECT_EQ(m.shape_std.size(), m.shape.size());
  }
}

TEST(MlRefine, SevenModesFivePercentNoise) {
  const Truth truth = SevenModes(16);
  const FitResult fit = Fit(SevenModeSet(0.05, 22), FitOptions{});
  ASSERT_TRUE(fit.refine.IsSolutionUsable()) << fit.refine.BriefReport();
  ASSERT_EQ(fit.modes.modes.size(), truth.modes.size());
  for (const auto& t : truth.modes) {
    const int k = Nearest(fit.modes, t.f_hz);
    ASSERT_GE(k, 0) << t.f_hz;
    const Mode& m = fit.modes.modes[k];
    // Issue 18 acceptance at 5 % noise: zeta within 5 % (relative); f still within 0.05 %.
    EXPECT_NEAR(m.damping_ratio / t.zeta, 1.0, 0.05) << t.f_hz;
    EXPECT_NEAR(m.frequency_hz / t.f_hz, 1.0, 5e-4) << t.f_hz;
  }
}

TEST(MlRefine, RefineNoneKeepsPolymaxValuesWithSigma) {
  const FrfSet frfs = SevenModeSet(0.01, 21);
  FitOptions none;
  none.refine = RefineMethod::kNone;
  const FitResult a = Fit(frfs, none);
  ASSERT_FALSE(a.selected.empty());
  for (size_t r = 0; r < a.modes.modes.size(); ++r) {
    // The PolyMAX pole itself, untouched (exactly: same double).
    EXPECT_EQ(a.modes.modes[r].pole, a.selected[r].pole.lambda);
    EXPECT_TRUE(std::isfinite(a.modes.modes[r].frequency_std_hz));
  }
  EXPECT_EQ(a.refine.iterations, 0);
}

// Monte Carlo (fixed seeds): 100 noise realisations of a 3-mode model. Bias of f and zeta within 3
// standard errors of zero; the ±1 sigma band holds the truth in 68 ± 10 % of the realisations.
struct McStats {
  std::vector<double> f_err, f_sd, z_err, z_sd;
};

/// Adds one realisation's errors and σ of each true mode (the fitted mode nearest it) to stats.
void Collect(const FitResult& fit, const std::vector<double>& f, const std::vector<double>& z, std::vector<McStats>* stats) {
  for (size_t r = 0; r < f.size(); ++r) {
    const int k = Nearest(fit.modes, f[r]);
    ASSERT_GE(k, 0);
    const Mode& m = fit.modes.modes[k];
    (*stats)[r].f_err.push_back(m.frequency_hz - f[r]);
    (*stats)[r].f_sd.push_back(m.frequency_std_hz);
    (*stats)[r].z_err.push_back(m.damping_ratio - z[r]);
    (*stats)[r].z_sd.push_back(m.damping_ratio_std);
  }
}

void CheckMonteCarlo(const std::vector<McStats>& stats, const std::vector<double>& f, const std::vector<double>& z) {
  for (size_t r = 0; r < stats.size(); ++r) {
    const McStats& s = stats[r];
    const int n = static_cast<int>(s.f_err.size());
    ASSERT_GE(n, 50);
    auto mean = [](const std::vector<double>& v) {
      double a = 0;
      for (double x : v) a += x;
      return a / v.size();
    };
    auto stdev = [&](const std::vector<double>& v) {
      const double mu = mean(v);
      double a = 0;
      for (double x : v) a += (x - mu) * (x - mu);
      return std::sqrt(a / (v.size() - 1));
    };
    // Bias: |mean error| < 3 standard errors (a 0.3 % false-alarm rate per check for an unbiased
    // estimator; the LS PolyMAX damping bias at this noise is ~10 standard errors).
    EXPECT_LT(std::abs(mean(s.f_err)), 3.0 * stdev(s.f_err) / std::sqrt(n)) << "f bias, mode " << f[r];
    EXPECT_LT(std::abs(mean(s.z_err)), 3.0 * stdev(s.z_err) / std::sqrt(n)) << "zeta bias, mode " << z[r];
    // Coverage of ±1 sigma: 68 % ± 10 % (binomial sd for 100 draws is 4.7 %, so ±10 % is ~2.1 sd).
    int f_in = 0, z_in = 0;
    for (int k = 0; k < n; ++k) {
      f_in += std::abs(s.f_err[k]) <= s.f_sd[k];
      z_in += std::abs(s.z_err[k]) <= s.z_sd[k];
    }
    double fsd = 0, zsd = 0;
    for (int k = 0; k < n; ++k) fsd += s.f_sd[k] / n, zsd += s.z_sd[k] / n;
    std::printf("mode %g: f bias %.2e sd %.2e mean sigma %.2e | z bias %.2e sd %.2e mean sigma %.2e\n", f[r], mean(s.f_err),
                stdev(s.f_err), fsd, mean(s.z_err), stdev(s.z_err), zsd);
    EXPECT_NEAR(static_cast<double>(f_in) / n, 0.68, 0.10) << "f coverage, mode " << f[r];
    EXPECT_NEAR(static_cast<double>(z_in) / n, 0.68, 0.10) << "zeta coverage, mode " << f[r];
  }
}

TEST(MlRefine, MonteCarloBiasAndCoverageResidualNoise) {
  const std::vector<double> f = {40.0, 61.0, 88.0}, z = {0.01, 0.02, 0.015};
  const Truth truth = MakeTruth(f, z, 6);
  std::vector<McStats> stats(f.size());
  FitOptions options;
  options.polymax.order_max = 20;
  options.select_frequencies_hz = f;  // the selection is not under test here
  for (unsigned seed = 100; seed < 200; ++seed) {
    const FrfSet frfs = MakeFrfSet(truth, {1, 4}, 120.0, 0.1, 0.05, seed);
    const FitResult fit = Fit(frfs, options);
    ASSERT_TRUE(fit.refine.IsSolutionUsable()) << seed << ": " << fit.refine.BriefReport();
    ASSERT_NO_FATAL_FAILURE(Collect(fit, f, z, &stats));
  }
  CheckMonteCarlo(stats, f, z);
}

// The same with a frequency-dependent noise level carried by the coherence (what `ema frf`
// writes): var = |H|^2 (1 - coh) / (n coh) with n = 5 averages, so the weights come from the data.
TEST(MlRefine, MonteCarloBiasAndCoverageCoherenceNoise) {
  const std::vector<double> f = {40.0, 61.0, 88.0}, z = {0.01, 0.02, 0.015};
  const Truth truth = MakeTruth(f, z, 6);
  std::vector<McStats> stats(f.size());
  FitOptions options;
  options.polymax.order_max = 20;
  options.select_frequencies_hz = f;
  for (unsigned seed = 200; seed < 300; ++seed) {
    FrfSet frfs = MakeFrfSet(truth, {1, 4}, 120.0, 0.1, 0.0, seed);
    std::mt19937 rng(seed);
    std::normal_distribution<double> g(0.0, 1.0);
    const int n_avg = 5;
    frfs.averages = Eigen::MatrixXi::Constant(frfs.ReferenceCount(), frfs.OutputCount(), n_avg);
    for (int r = 0; r < frfs.ReferenceCount(); ++r) {
      frfs.coherence.push_back(Eigen::MatrixXd(frfs.h[r].rows(), frfs.h[r].cols()));
      for (int o = 0; o < frfs.OutputCount(); ++o) {
        const double rms = std::sqrt(frfs.h[r].col(o).squaredNorm() / frfs.LineCount());
        for (int k = 0; k < frfs.LineCount(); ++k) {
          // Noise rising 4x across the band (a force spectrum rolling off), 3 % of the RMS at DC.
          const double sd = 0.03 * rms * (1.0 + 3.0 * frfs.frequency_hz[k] / 120.0);
          frfs.h[r](k, o) += sd * std::complex<double>(g(rng), g(rng)) / std::sqrt(2.0);
          // The coherence an H1 estimate would carry with this noise: |H|^2 (1 - coh)/(n coh) = sd^2
          // with the measured (noisy) |H|, as ema frf's Gxy, Gxx, Gyy give it.
          const double h2 = std::norm(frfs.h[r](k, o));
          frfs.coherence[r](k, o) = h2 / (h2 + n_avg * sd * sd);
        }
      }
    }
    const FitResult fit = Fit(frfs, options);
    ASSERT_TRUE(fit.refine.IsSolutionUsable()) << seed << ": " << fit.refine.BriefReport();
    ASSERT_EQ(fit.refine.noise_source, NoiseSource::kCoherence);
    ASSERT_NO_FATAL_FAILURE(Collect(fit, f, z, &stats));
  }
  CheckMonteCarlo(stats, f, z);
}

TEST(MlRefineOptions, DefaultsAreValidAndBadValuesNamed) {
  std::string error;
  EXPECT_TRUE(MlRefineOptions{}.IsValid(&error));
  MlRefineOptions bad;
  bad.max_iterations = 0;
  EXPECT_FALSE(bad.IsValid(&error));
  EXPECT_NE(error.find("max_iterations"), std::string::npos);
  RefineMethod method;
  EXPECT_TRUE(StringToRefineMethod("none", &method));
  EXPECT_EQ(method, RefineMethod::kNone);
  EXPECT_FALSE(StringToRefineMethod("ML", &method));
}

TEST(MlRefine, ModalModelReproducesTheNoiseFreeData) {
  // Noise-free: the model the fit reports (poles, residues, residual terms) is the data.
  const FrfSet frfs = MakeFrfSet(SevenModes(6), {1, 4}, 500.0, 0.25, 0.0, 1);
  const FitResult fit = Fit(frfs, FitOptions{});
  ASSERT_EQ(fit.modes.modes.size(), 7u);
  const ModalModel& model = fit.model;
  double err = 0.0, ref = 0.0;
  const Eigen::VectorXd f = frfs.frequency_hz.tail(frfs.LineCount() - 1);
  for (int o = 0; o < static_cast<int>(model.outputs.size()); ++o)
    for (int i = 0; i < static_cast<int>(model.references.size()); ++i) {
      const Eigen::VectorXcd h = SynthesiseFrf(model, o, i, f);
      const Eigen::VectorXcd meas = frfs.h[i].col(o).tail(f.size());
      err += (h - meas).squaredNorm();
      ref += meas.squaredNorm();
    }
  // Noise-free data, exact poles: the relative misfit is at rounding level (1e-6 leaves room for
  // the pole accuracy of ~1e-8).
  EXPECT_LT(std::sqrt(err / ref), 1e-6);
}

}  // namespace
}  // namespace ema::curvefit

namespace ema::curvefit {
namespace {

// Roving-set inconsistency (issue 18 point 4): the 50 Hz mode is measured at 50.0 Hz on outputs
// 1-6 and at 50.4 Hz on outputs 7-12 (sensor mass loading differs between the two sets; the
// half-power bands, 0.5 Hz each side, overlap). PolyMAX finds two poles with the same
// participation and disjoint shapes; automatic selection must report one mode and say why.
TEST(SplitPoles, RovingSetInconsistencyGivesOneMode) {
  const Truth a = MakeTruth({30.0, 50.0, 80.0}, {0.01, 0.01, 0.01}, 12);  // the true shapes
  const FrfSet frfs = test::TwoRovingSetsWithShiftedMode(50.4);
  FitOptions options;
  options.polymax.order_max = 40;
  const FitResult fit = Fit(frfs, options);
  ASSERT_EQ(fit.modes.modes.size(), 3u) << "one pole per physical mode";
  ASSERT_EQ(fit.dropped.size(), 1u);
  EXPECT_NEAR(fit.dropped[0].frequency_hz, 50.2, 0.3);
  EXPECT_NE(fit.dropped[0].reason.find("other outputs"), std::string::npos);
  const int k = Nearest(fit.modes, 50.2);
  ASSERT_GE(k, 0);
  // The kept mode carries the whole shape: MAC with the true shape (both sets alike) >= 0.95.
  EXPECT_GE(ComplexMac(fit.modes.modes[k].shape, a.modes[1].shape.cast<std::complex<double>>()), 0.95);
  // Without the check, the same data give four poles (the test can fail).
  options.split_poles.enabled = false;
  EXPECT_EQ(Fit(frfs, options).modes.modes.size(), 4u);
}

}  // namespace
}  // namespace ema::curvefit
