// The pick page's own files, embedded at build time with the assembler's .incbin as the report
// embeds its assets (app/report/embedded_assets.cpp); app/CMakeLists.txt passes their paths.
#include <string>

#include "embed_file.hpp"
#include "embedded_assets.hpp"
#include "pick/pick_page.hpp"

EMA_EMBED(ema_pick_html, EMA_PICK_HTML_PATH)
EMA_EMBED(ema_pick_js, EMA_PICK_JS_PATH)

namespace ema::app {

namespace {

// A script's text may not close its own <script> element.
std::string ScriptSafe(std::string_view js) {
  std::string text(js);
  for (size_t at = text.find("</script"); at != std::string::npos; at = text.find("</script", at + 3)) text.replace(at, 2, "<\\/");
  return text;
}

void ReplaceOnce(std::string* text, const std::string& marker, const std::string& with) {
  const size_t at = text->find(marker);
  if (at != std::string::npos) text->replace(at, marker.size(), with);
}

}  // namespace

std::string_view PickHtml() { return {ema_pick_html_begin, ema_pick_html_end}; }
std::string_view PickJs() { return {ema_pick_js_begin, ema_pick_js_end}; }

std::string PickPageHtml() {
  std::string html(PickHtml());
  // The script goes in first: the plotly bundle is large and need not be searched for markers.
  ReplaceOnce(&html, "/*EMA_PICK_JS*/", ScriptSafe(PickJs()));
  ReplaceOnce(&html, "/*EMA_PLOTLY_JS*/", ScriptSafe(report::PlotlyJs()));
  return html;
}

}  // namespace ema::app
