// The HTML report of `ema run` on synthetic results with known truth: the data preparation (the
// correlation's MAC as given, the fit's modal model as the fit curve, stabilisation reading)
// against hand values, and the page in headless Chromium.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <random>

#include "browser_check.hpp"
#include "report.hpp"

namespace ema::report {
namespace {

using json = nlohmann::json;
namespace fs = std::filesystem;

// A 3-mode system on 4 nodes × 3 directions (mass-normalised shapes), accelerance FRFs.
struct Truth {
  std::vector<double> f_hz{120.0, 185.0, 260.0};
  std::vector<double> zeta{0.02, 0.015, 0.03};
  std::vector<Node> nodes{{1, {0.0, 0.0, 0.0}}, {2, {0.2, 0.0, 0.0}}, {3, {0.2, 0.1, 0.0}}, {4, {0.0, 0.1, 0.05}}};
  Eigen::MatrixXd shapes;  // 12 × 3
  std::vector<Dof> dofs;
  Truth() {
    for (const Node& n : nodes)
      for (int d = 1; d <= 3; ++d) dofs.push_back({n.id, d});
    shapes.resize(12, 3);
    for (int i = 0; i < 12; ++i)
      for (int m = 0; m < 3; ++m) shapes(i, m) = 0.1 * std::cos(0.7 * (i + 1) * (m + 1)) + (m == i % 3 ? 0.15 : 0.0);
  }
  std::complex<double> H(int out, int ref, double f) const {
    const double w = kTwoPi * f;
    std::complex<double> h = 0.0;
    for (int m = 0; m < 3; ++m) {
      const double wr = kTwoPi * f_hz[m];
      h += -w * w * shapes(out, m) * shapes(ref, m) / std::complex<double>(wr * wr - w * w, 2 * zeta[m] * wr * w);
    }
    return h;
  }
  /// The fit's modal model for the FRFs from node 1 +Z (dofs[2]) to every DOF: receptance
  /// residues phi_o phi_ref / (2j w_d), accelerance, band [lo_hz, hi_hz].
  curvefit::ModalModel ModalModel(double lo_hz, double hi_hz) const {
    curvefit::ModalModel model;
    model.outputs = dofs;
    model.references = {dofs[2]};
    model.frf_type = FrfType::kAccelerance;
    model.band_lo_hz = lo_hz;
    model.band_hi_hz = hi_hz;
    model.residues.resize(12, 3);
    for (int m = 0; m < 3; ++m) {
      const std::complex<double> p = FrequencyAndDampingToPole(f_hz[m], zeta[m]);
      model.poles_fitted.push_back(p);
      for (int o = 0; o < 12; ++o) model.residues(o, m) = shapes(o, m) * shapes(2, m) / std::complex<double>(0.0, 2.0 * p.imag());
    }
    model.lower_residual = model.upper_residual = Eigen::VectorXd::Zero(12);
    return model;
  }
  ModeSet Modes(double frequency_factor, double shape_noise, unsigned seed) const {
    std::mt19937 rng(seed);
    std::normal_distribution<double> noise(0.0, shape_noise);
    ModeSet set;
    set.dofs = dofs;
    for (int m = 0; m < 3; ++m) {
      Mode mode;
      mode.frequency_hz = f_hz[m] * frequency_factor;
      mode.damping_ratio = zeta[m];
      mode.shape.resize(12);
      for (int i = 0; i < 12; ++i) mode.shape[i] = shapes(i, m) * (1 + noise(rng));
      set.modes.push_back(mode);
    }
    return set;
  }
};

FrfSet MakeFrfs(const Truth& truth, double noise_level, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, 1.0);
  FrfSet frfs;
  const int lines = 401;
  frfs.frequency_hz = Eigen::VectorXd::LinSpaced(lines, 0.0, 400.0);
  frfs.outputs = truth.dofs;
  frfs.references = {truth.dofs[2]};  // node 1 +Z
  frfs.h.assign(1, Eigen::MatrixXcd(lines, 12));
  for (int o = 0; o < 12; ++o)
    for (int i = 0; i < lines; ++i) {
      const std::complex<double> h = truth.H(o, 2, frfs.frequency_hz[i]);
      frfs.h[0](i, o) = h * (1.0 + noise_level * std::complex<double>(noise(rng), noise(rng)));
    }
  return frfs;
}

// The correlation step's result, with its own MAC matrix (test rows), which the report shows as given.
CorrelationView Correlation(const Truth& truth, const ModeSet& test, double factor) {
  CorrelationView view;
  view.test = test;
  view.model = truth.Modes(factor, 0.05, 2);
  correlation::CorrelationResult& r = view.result;
  double sum = 0.0;
  for (int m = 0; m < 3; ++m) {
    correlation::CorrelationRow row;
    row.test_mode = row.model_mode = m;
    row.test_frequency_hz = truth.f_hz[m];
    row.model_frequency_hz = truth.f_hz[m] * factor;
    row.agreement_pct = 100.0 * (1.0 - std::abs(row.model_frequency_hz - row.test_frequency_hz) / row.model_frequency_hz);
    row.mac = 0.99;
    sum += row.agreement_pct;
    r.rows.push_back(row);
    r.pairing.pairs.push_back({m, m, 0.99});
  }
  r.mac.resize(3, 3);
  r.mac << 0.99, 0.02, 0.01, 0.03, 0.98, 0.04, 0.0, 0.05, 0.97;
  r.shared_dof_count = r.test_dof_count = 12;
  r.mean_agreement_pct = r.min_agreement_pct = sum / 3;
  r.mean_mac = 0.99;
  return view;
}

ReportInput MakeInput() {
  Truth truth;
  SetupResults setup;
  setup.name = "synthetic";
  setup.frfs = MakeFrfs(truth, 0.01, 7);
  setup.band_lo_hz = 60.0;
  setup.band_hi_hz = 330.0;
  curvefit::FitResult fit;
  fit.modes = truth.Modes(1.0, 0.02, 1);
  fit.model = truth.ModalModel(60.0, 330.0);
  setup.correlation_before = Correlation(truth, fit.modes, 1.6);
  setup.correlation_after = Correlation(truth, fit.modes, 1.005);
  setup.fit = fit;
  // Stabilisation: true poles stable from order 6 on, plus a wandering spurious pole per order.
  json orders = json::array();
  for (int order = 2; order <= 40; order += 2) {
    json poles = json::array();
    for (int m = 0; m < 3; ++m)
      if (order >= 2 * (m + 1))
        poles.push_back({{"frequency_hz", truth.f_hz[m] * (1 + 0.002 / order)}, {"damping_ratio", truth.zeta[m]},
                         {"status", order >= 6 ? "stable" : "unstable"}});
    poles.push_back({{"frequency_hz", 70.0 + 6.5 * order}, {"damping_ratio", 0.08}, {"status", "unstable"}});
    orders.push_back({{"order", order}, {"poles", poles}});
  }
  setup.stabilisation = {{"orders", orders}};
  setup.geometry = truth.nodes;
  setup.lines = {{1, 2}, {2, 3}, {3, 4}, {4, 1}};
  setup.frf_summary = {{"frfs", {{{"response_node", 2}, {"response_dir", "+Z"}, {"reference_node", 1},
                                  {"reference_dir", "+Z"}, {"averages", 4},
                                  {"rejected", {{{"impact", 3}, {"reason", "double hit"}}}}}}}};
  ReportInput input;
  input.title = "Synthetic report";
  input.subtitle = "tests/app/report_test.cpp";
  input.summary = {"line one", "line two"};
  input.setups.push_back(setup);
  input.diagnosis = {
      {"baseline", {{"mean_abs_frequency_error_pct", 37.5}, {"mean_mac", 0.97}}},
      {"candidates",
       {{{"rank", 1}, {"kind", "series_compliance"}, {"target", "bearings"}, {"parameters", {{"k", 3.2e6}}},
         {"mean_abs_frequency_error_pct", 0.4}, {"mean_mac", 0.99}, {"score", -20.0}},
        {{"rank", 2}, {"kind", "stiffness_scale"}, {"target", "bearings"}, {"parameters", {{"factor", 0.4}}},
         {"mean_abs_frequency_error_pct", 6.1}, {"mean_mac", 0.98}, {"score", 3.0}}}}};
  return input;
}

TEST(ReportData, ShapesFoldNegativeDirections) {
  // A value measured along -Z is drawn as the opposite value along +Z (the animated shape).
  ReportInput input = MakeInput();
  SetupResults& setup = input.setups[0];
  setup.geometry = {{5, {0.0, 0.0, 0.0}}};
  ModeSet& modes = setup.fit->modes;
  modes.dofs = {{5, -3}, {5, 1}};
  modes.modes.resize(1);
  modes.modes[0].shape = Eigen::VectorXcd(2);
  modes.modes[0].shape << std::complex<double>(2.0, 1.0), std::complex<double>(1.0, 0.0);
  const json shape = BuildReportData(input)["setups"][0]["shapes"]["modes"][0]["shape"][0];
  const double largest = std::abs(std::complex<double>(2.0, 1.0));
  ASSERT_EQ(shape.size(), 6u);  // re x, re y, re z, im x, im y, im z
  EXPECT_NEAR(shape[0].get<double>(), 1.0 / largest, 1e-5);  // 5 significant digits on the page
  EXPECT_NEAR(shape[2].get<double>(), -2.0 / largest, 1e-5);
  EXPECT_NEAR(shape[5].get<double>(), -1.0 / largest, 1e-5);
}

TEST(ReportData, FitCurveIsTheFitsOwnModalModel) {
  // The truth as the fit's modal model must reproduce the analytic FRF on the band (the page
  // rounds to 5 significant digits) and be absent outside it: the report evaluates the fit's
  // model (curvefit::SynthesiseMeasuredFrf) and re-fits nothing.
  Truth truth;
  const json frf = BuildReportData(MakeInput())["setups"][0]["frf"];
  const json& f = frf["frequency_hz"];
  for (int o : {0, 5, 11}) {
    const json& item = frf["frfs"][o];
    for (std::size_t i = 0; i < f.size(); ++i) {
      const double hz = f[i].get<double>();
      if (hz < 60.0 || hz > 330.0) {
        EXPECT_TRUE(item["fit_magnitude"][i].is_null()) << hz;
        continue;
      }
      const double exact = std::abs(truth.H(o, 2, hz));
      EXPECT_NEAR(item["fit_magnitude"][i].get<double>(), exact, 1e-4 * exact) << "output " << o << " at " << hz << " Hz";
    }
  }
}

TEST(ReportData, StabilisationLayouts) {
  const json nested = {{"orders", {{{"order", 4}, {"poles", {{{"frequency_hz", 100.0}, {"damping_ratio", 0.01},
                                                              {"stable", true}}}}}}}};
  const json flat = {{"poles", {{{"order", 6}, {"frequency_hz", 50.0}, {"damping_ratio", 0.02},
                                 {"stable_frequency", true}, {"stable_damping", false}}}}};
  const StabilisationPoints a = ReadStabilisation(nested), b = ReadStabilisation(flat);
  ASSERT_EQ(a.order.size(), 1u);
  EXPECT_EQ(a.order[0], 4);
  EXPECT_EQ(a.status[0], "stable");
  ASSERT_EQ(b.order.size(), 1u);
  EXPECT_EQ(b.order[0], 6);
  EXPECT_EQ(b.status[0], "unstable");  // damping not stable
}

TEST(Report, PageIsSelfContainedAndCarriesTheData) {
  const std::string html = RenderHtml(MakeInput());
  // No external resource: no src/href to http(s) in script or link tags.
  EXPECT_EQ(html.find("<script src"), std::string::npos);
  EXPECT_EQ(html.find("<link "), std::string::npos);
  EXPECT_NE(html.find("plotly.js v"), std::string::npos);
  const json data = BuildReportData(MakeInput());
  ASSERT_EQ(data["setups"].size(), 1u);
  EXPECT_EQ(data["setups"][0]["correlation_before"]["pairs"].size(), 3u);
  EXPECT_EQ(data["setups"][0]["frf"]["frfs"].size(), 12u);
  EXPECT_EQ(data["setups"][0]["mac_before"]["shared_dofs"], 12);
  EXPECT_EQ(data["setups"][0]["mac_before"]["values"][1][1], 0.98);  // the correlation's value, as given
  // The FRF chart's fit is the test modes' modal model: on the band it is finite.
  int finite = 0;
  for (const json& v : data["setups"][0]["frf"]["frfs"][0]["fit_magnitude"]) finite += v.is_number();
  EXPECT_GT(finite, 100);
  EXPECT_EQ(data["setups"][0]["shapes"]["modes"].size(), 3u);
  ASSERT_EQ(data["setups"][0]["test_mode_table"]["modes"].size(), 3u);
  EXPECT_EQ(data["setups"][0]["test_mode_table"]["modes"][1]["frequency_hz"], 185.0);
  EXPECT_EQ(data["setups"][0]["rejected"].size(), 1u);
}

TEST(Report, RendersInHeadlessChromium) {
  if (!test::ChromiumAvailable()) {
    if (!test::BrowserCheckMayBeSkipped()) FAIL() << "chromium missing in CI (scripts/install-deps.sh --test installs it)";
    GTEST_SKIP() << "chromium not installed (scripts/install-deps.sh --test)";
  }
  const fs::path dir = fs::path(EMA_TEST_TMP_DIR) / "report_synthetic";
  fs::create_directories(dir);
  {
    std::ofstream out(dir / "report.html", std::ios::binary);
    out << RenderHtml(MakeInput());
  }
  const test::BrowserResult r = test::CheckInChromium(dir / "report.html", dir / "browser");
  ASSERT_TRUE(r.ran);
  EXPECT_EQ(r.page_errors, "");
  EXPECT_EQ(r.console_errors, "");
  // 1 stabilisation + 1 FRF + 2 MAC + 1 mode shape + 2 diagnosis charts.
  EXPECT_EQ(r.expected, 7);
  EXPECT_EQ(r.rendered, r.expected);
  EXPECT_EQ(r.rendered_divs, r.expected);
}

}  // namespace
}  // namespace ema::report
