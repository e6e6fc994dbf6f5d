// The report's "Data quality" section, the CMIF/MMIF on the stabilisation diagram, chart export
// (PNG and SVG with the title) and printing to PDF, in headless Chromium.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "app/browser_check.hpp"
#include "curvefit/synthetic.hpp"
#include "ema/formats/mode_indicators_json.hpp"
#include "ema/formats/quality_json.hpp"
#include "ema/frf/quality.hpp"
#include "report.hpp"
#include "report_quality.hpp"

namespace ema::report {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

// Two references, coherence with a low-frequency dip on one FRF, a reciprocal pair 10 % off.
ReportInput MakeQualityInput() {
  auto truth = curvefit::test::MakeTruth({40.0, 100.0, 102.0}, {0.01, 0.02, 0.02}, 4);
  FrfSet frfs = curvefit::test::MakeFrfSet(truth, {0, 1}, 150.0, 0.25, 0.0, 5);
  frfs.coherence.assign(2, Eigen::MatrixXd::Constant(frfs.LineCount(), 4, 0.98));
  frfs.coherence[0](10, 3) = 0.2;  // one bad line on FRF 4/1
  frfs.averages = Eigen::MatrixXi::Constant(2, 4, 5);
  frfs.h[0].col(1) *= 1.1;
  SetupResults setup;
  setup.name = "quality";
  frf::QualityOptions options;
  setup.quality = formats::QualityJson(frf::CheckFrfQuality({frfs}, options, {"frf.unv"}), {}, options);
  json orders = json::array();
  for (int order = 2; order <= 20; order += 2)
    orders.push_back({{"order", order},
                      {"poles", {{{"frequency_hz", 40.0}, {"damping_ratio", 0.01}, {"status", "stable"}},
                                 {{"frequency_hz", 100.0}, {"damping_ratio", 0.02}, {"status", "stable"}}}}});
  setup.stabilisation = {{"orders", orders}};
  formats::AddModeIndicatorsJson(&setup.stabilisation, frfs, {}, "frf.unv");
  Mode mode;
  mode.frequency_hz = 40.0;
  mode.damping_ratio = 0.01;
  mode.mpc = 0.999;
  mode.mpd = 1.2;
  mode.mcf = 0.001;
  setup.fit = curvefit::FitResult();
  setup.fit->modes.modes = {mode};
  setup.frfs = frfs;
  ReportInput input;
  input.title = "Quality report";
  input.setups.push_back(setup);
  return input;
}

TEST(ReportQuality, DataCarriesTheChecksAndTheIndicators) {
  const json data = BuildReportData(MakeQualityInput());
  const json& q = data["setups"][0]["quality"];
  EXPECT_EQ(q["verdict"], "warn");
  ASSERT_EQ(q["reciprocity"].size(), 1u);
  EXPECT_EQ(q["reciprocity"][0]["verdict"], "warn");
  const json& map = q["coherence_map"];
  ASSERT_EQ(map["labels"].size(), 8u);
  ASSERT_EQ(map["z"].size(), 8u);
  // 600 band lines binned by 2 into 300 columns, each the minimum of its lines: the single bad
  // line (line 10 = band line 9) shows in column 4.
  EXPECT_EQ(map["step"], 2);
  EXPECT_EQ(map["z"][3].size(), 300u);
  EXPECT_DOUBLE_EQ(map["z"][3][4].get<double>(), 0.2);
  EXPECT_DOUBLE_EQ(map["z"][3][5].get<double>(), 0.98);
  EXPECT_DOUBLE_EQ(q["modes"][0]["mcf"].get<double>(), 0.001);
  // The test-modes table carries MPD and MCF beside MPC, as ema fit wrote them.
  const json& tm = data["setups"][0]["test_mode_table"]["modes"][0];
  EXPECT_DOUBLE_EQ(tm["mpd_deg"].get<double>(), 1.2);
  EXPECT_DOUBLE_EQ(tm["mcf"].get<double>(), 0.001);
  const json& mi = data["setups"][0]["mode_indicators"];
  ASSERT_EQ(mi["cmif"].size(), 2u);
  EXPECT_EQ(mi["cmif"][0].size(), mi["frequency_hz"].size());
  EXPECT_EQ(mi["mmif"].size(), mi["frequency_hz"].size());
  // Without the inputs, the section's data is empty (the page says "not available").
  EXPECT_TRUE(QualityData(json(), json()).empty());
  EXPECT_TRUE(ModeIndicatorData(json::object()).empty());
}

TEST(ReportQuality, RendersExportsEveryChartAndPrintsToPdf) {
  if (!test::ChromiumAvailable()) {
    if (!test::BrowserCheckMayBeSkipped()) FAIL() << "chromium missing in CI (scripts/install-deps.sh --test installs it)";
    GTEST_SKIP() << "chromium not installed (scripts/install-deps.sh --test)";
  }
  const fs::path dir = fs::path(EMA_TEST_TMP_DIR) / "report_quality";
  fs::remove_all(dir);
  fs::create_directories(dir);
  {
    std::ofstream out(dir / "report.html", std::ios::binary);
    out << RenderHtml(MakeQualityInput());
  }
  const test::BrowserResult r = test::CheckInChromium(dir / "report.html", dir / "browser", "#export-check");
  ASSERT_TRUE(r.ran);
  EXPECT_EQ(r.page_errors, "");
  EXPECT_EQ(r.console_errors, "");
  // Coherence heatmap, stabilisation diagram (with CMIF/MMIF), FRF chart.
  EXPECT_EQ(r.expected, 3);
  EXPECT_EQ(r.rendered, r.expected);
  // Every chart exported as SVG holding its title and as a PNG.
  EXPECT_EQ(r.exported_svg, r.expected);
  EXPECT_EQ(r.exported_png, r.expected);
  const std::string dom = test::Slurp(dir / "browser" / "dom.html");
  EXPECT_NE(dom.find("Data quality — quality"), std::string::npos);
  EXPECT_NE(dom.find("Download SVG (with title)"), std::string::npos);  // the modebar buttons
  EXPECT_NE(dom.find("Download PNG (with title)"), std::string::npos);
  EXPECT_LT(dom.find("Data quality — quality"), dom.find("Stabilisation diagram — quality"));

  // Print to PDF as a user would (Chromium's print path, the page's @media print rules). Without
  // --virtual-time-budget: Chromium 156.0.8078.129 (Debian, December 2026) never returns from a
  // print under a virtual time budget (the test stalled until ctest's 900 s); the charts are drawn
  // by the load event the print waits for. `timeout`: a hang fails here, in two minutes.
  const fs::path pdf = dir / "report.pdf";
  const std::string command =
      "timeout -k 10 120 chromium --headless --no-sandbox --disable-gpu --no-first-run --disable-background-networking "
      "--disable-component-update --disable-sync --disable-dev-shm-usage "
      "--no-pdf-header-footer --user-data-dir='" + (dir / "profile-pdf").string() + "' --print-to-pdf='" +
      pdf.string() + "' 'file://" + fs::absolute(dir / "report.html").string() + "' > '" +
      (dir / "pdf.log").string() + "' 2>&1";
  ASSERT_EQ(std::system(command.c_str()), 0) << test::Slurp(dir / "pdf.log");
  const std::string bytes = test::Slurp(pdf);
  ASSERT_EQ(bytes.rfind("%PDF-", 0), 0u);
  int pages = 0;
  for (size_t at = bytes.find("/Type /Page"); at != std::string::npos; at = bytes.find("/Type /Page", at + 1))
    pages += bytes.compare(at, 12, "/Type /Pages") != 0;  // page objects, not the page tree
  EXPECT_GE(pages, 2);  // summary-free page: the test's page break plus its cards
  EXPECT_GT(bytes.size(), 20000u);
}

}  // namespace
}  // namespace ema::report
