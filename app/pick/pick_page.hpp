// The page of `ema pick`: app/pick/pick.html with plotly.js (the report's bundle, ema_report) and
// app/pick/pick.js inlined, all embedded in the binary at build time (pick_assets.cpp). The page
// loads nothing from the network; it reads its token from its own URL and asks the server for the
// data (GET /api/data) and for every pick (POST /api/select).
#pragma once

#include <string>
#include <string_view>

namespace ema::app {

/// The page's markup and style sheet (app/pick/pick.html).
std::string_view PickHtml();
/// The page's script (app/pick/pick.js): window.emaPick, the charts, the clicks.
std::string_view PickJs();

/// The complete page (no data in it: the page fetches it with its token).
std::string PickPageHtml();

}  // namespace ema::app
