// Assets embedded at build time with the assembler's .incbin: plotly.js (from `npm ci`, see
// CMakeLists.txt) and the report's own script and style sheet. A trailing NUL is appended to each.
#include "embedded_assets.hpp"
#include "embed_file.hpp"

EMA_EMBED(ema_report_plotly_js, EMA_PLOTLY_JS_PATH)
EMA_EMBED(ema_report_js, EMA_REPORT_JS_PATH)
EMA_EMBED(ema_report_css, EMA_REPORT_CSS_PATH)

namespace ema::report {

std::string_view PlotlyJs() { return {ema_report_plotly_js_begin, ema_report_plotly_js_end}; }
std::string_view ReportJs() { return {ema_report_js_begin, ema_report_js_end}; }
std::string_view ReportCss() { return {ema_report_css_begin, ema_report_css_end}; }

}  // namespace ema::report
