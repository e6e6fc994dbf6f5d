// The report's amplitude section (issue 14): frequency and damping against level per mode, drawn
// from the `ema amplitude --json` object.
#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "browser_check.hpp"
#include "report.hpp"

namespace ema::report {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

json Amplitude() {
  json levels = json::array(), flat = json::array();
  const double f[4] = {251.3, 250.8, 249.4, 245.3}, z[4] = {0.0055, 0.0064, 0.0087, 0.0132};
  const double lv[4] = {1.8, 4.3, 9.9, 27.2};
  for (int i = 0; i < 4; ++i) {
    levels.push_back({{"level", lv[i]}, {"frequency_hz", f[i]}, {"damping_ratio", z[i]}, {"frequency_std_hz", 0.05},
                      {"damping_ratio_std", nullptr}, {"poles", 1}});
    flat.push_back({{"level", lv[i]}, {"frequency_hz", 301.6}, {"damping_ratio", 0.005}, {"frequency_std_hz", nullptr},
                    {"damping_ratio_std", nullptr}, {"poles", 1}});
  }
  return {{"level_kind", "peak_force"},
          {"levels", {1.8, 4.3, 9.9, 27.2}},
          {"modes",
           {{{"mode", 1}, {"levels", levels}, {"frequency_trend", "softening"}, {"frequency_change_pct", -2.4},
             {"damping_trend", "rising"}, {"damping_ratio_factor", 2.4},
             {"reading", "micro-slip in a joint: f \u22122.38 %, \u03b6 \u00d72.4 from 1.8 to 27.2 N"}},
            {{"mode", 2}, {"levels", flat}, {"frequency_trend", "none"}, {"frequency_change_pct", 0.0},
             {"damping_trend", "none"}, {"damping_ratio_factor", 1.0}, {"reading", "linear within the scatter"}}}}};
}

TEST(ReportAmplitude, DataCarriesTheAmplitudeObjectOnlyWhenGiven) {
  ReportInput input;
  EXPECT_FALSE(BuildReportData(input).contains("amplitude"));
  input.amplitude = Amplitude();
  const json data = BuildReportData(input);
  ASSERT_TRUE(data.contains("amplitude"));
  EXPECT_EQ(data["amplitude"]["modes"].size(), 2u);
}

TEST(ReportAmplitude, OneChartPerModeRendersInHeadlessChromium) {
  if (!test::ChromiumAvailable()) GTEST_SKIP() << "chromium not installed (scripts/install-deps.sh --test)";
  const fs::path dir = fs::path(EMA_TEST_TMP_DIR) / ("report_amplitude_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  ReportInput input;
  input.title = "amplitude";
  input.amplitude = Amplitude();
  {
    std::ofstream out(dir / "report.html", std::ios::binary);
    out << RenderHtml(input);
  }
  const test::BrowserResult r = test::CheckInChromium(dir / "report.html", dir / "browser");
  ASSERT_TRUE(r.ran);
  EXPECT_EQ(r.page_errors, "");
  EXPECT_EQ(r.console_errors, "");
  EXPECT_EQ(r.expected, 2);  // f and ζ against level, one chart per mode
  EXPECT_EQ(r.rendered, r.expected);
  EXPECT_EQ(r.rendered_divs, r.expected);
}

}  // namespace
}  // namespace ema::report
