// Build-time embedded assets of the HTML report.
#pragma once

#include <string_view>

namespace ema::report {

/// plotly.js (plotly.js-dist-min, version pinned in app/report/package-lock.json), minified.
std::string_view PlotlyJs();
/// The report page's own script (app/report/report.js): draws every chart from the embedded data.
std::string_view ReportJs();
/// The report page's style sheet (app/report/report.css).
std::string_view ReportCss();

}  // namespace ema::report
