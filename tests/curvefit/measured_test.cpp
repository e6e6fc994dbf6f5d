// The measured free-free beam FRFs of tests/data/real/frf-meas-point (pyuff data, MIT): one
// accelerometer at node 1 (+X), a roving hammer at nodes 1, 2, 3; 0..1000 Hz at 1 Hz.
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>
#include <string>

#include "ema/curvefit/fit.hpp"

namespace ema::curvefit {
namespace {

/// Parses one "(re+imj)" per line (Python complex repr; "nan" allowed).
Eigen::VectorXcd ReadComplexColumn(const std::string& path) {
  std::ifstream in(path);
  EXPECT_TRUE(in.good()) << path;
  std::vector<std::complex<double>> v;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    std::string s = line;
    if (s.front() == '(') s = s.substr(1, s.size() - 2);
    if (!s.empty() && s.back() == 'j') s.pop_back();
    // Split at the sign of the imaginary part (not an exponent sign).
    size_t cut = std::string::npos;
    for (size_t k = 1; k < s.size(); ++k)
      if ((s[k] == '+' || s[k] == '-') && s[k - 1] != 'e' && s[k - 1] != 'E') cut = k;
    const double re = std::stod(s.substr(0, cut));
    const double im = cut == std::string::npos ? 0.0 : std::stod(s.substr(cut));
    v.emplace_back(re, im);
  }
  return Eigen::Map<Eigen::VectorXcd>(v.data(), static_cast<Eigen::Index>(v.size()));
}

FrfSet MeasuredBeam() {
  FrfSet set;
  set.outputs = {{1, 1}};
  for (int ref = 1; ref <= 3; ++ref) {
    set.references.push_back({ref, 1});
    Eigen::VectorXcd col = ReadComplexColumn(std::string(EMA_REAL_DATA_DIR) + "/frf-meas-point/meas_point_" +
                                             std::to_string(ref) + ".txt");
    set.h.push_back(col);
  }
  set.frequency_hz = Eigen::VectorXd::LinSpaced(set.h[0].rows(), 0.0, set.h[0].rows() - 1.0);
  set.output_quantity = Quantity::kAcceleration;
  set.roving_hammer = true;
  return set;
}

TEST(MeasuredBeam, AutomaticFitFindsTheSixPeaks) {
  const FrfSet frfs = MeasuredBeam();
  ASSERT_EQ(frfs.LineCount(), 1001);
  const FitResult fit = Fit(frfs, FitOptions{}, "meas-point");
  EXPECT_TRUE(fit.transposed);
  ASSERT_EQ(fit.modes.dofs.size(), 3u);  // shapes at the three hammer points
  std::ostringstream found;
  for (const auto& m : fit.modes.modes) found << m.frequency_hz << " Hz (" << m.damping_ratio << ") ";
  // The peaks of the data (README) sit at these lines; no published modal values exist, so a
  // fitted natural frequency must simply lie within 1.5 % of each (a few half-power widths).
  for (double f : {52.0, 142.0, 279.0, 460.0, 687.0, 959.0}) {
    bool hit = false;
    for (const auto& m : fit.modes.modes) hit = hit || std::abs(m.frequency_hz - f) < 0.015 * f;
    EXPECT_TRUE(hit) << "no mode near " << f << " Hz; found " << found.str();
  }
  // Nothing else: the beam has no other peak in 0..1000 Hz.
  EXPECT_EQ(fit.modes.modes.size(), 6u) << found.str();
  for (const auto& m : fit.modes.modes) {
    EXPECT_GT(m.damping_ratio, 0.0);
    EXPECT_LT(m.damping_ratio, 0.05);
  }
}

}  // namespace
}  // namespace ema::curvefit
