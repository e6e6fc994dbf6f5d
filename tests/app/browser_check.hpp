// Loads an HTML file in headless Chromium (Debian's `chromium`) and reports what the page said:
// how many charts it expected and rendered (body data attributes set by app/report/report.js),
// the errors it caught, and every console error Chromium logged.
#pragma once

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>

namespace ema::test {

struct BrowserResult {
  bool ran = false;            ///< chromium started and dumped the DOM
  int expected = -1;           ///< data-charts-expected
  int rendered = -1;           ///< data-charts-rendered (set once every Plotly.newPlot resolved)
  std::string page_errors;     ///< data-errors (window.onerror / rejected promises)
  std::string console_errors;  ///< console messages at error level and uncaught exceptions
  int rendered_divs = 0;       ///< chart divs holding an SVG or WebGL/3D plot
  int exported_svg = -1;       ///< data-export-svg (page opened with #export-check)
  int exported_png = -1;       ///< data-export-png
};

inline std::string ReadWhole(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

/// `fragment` (e.g. "#export-check") is appended to the page's URL.
inline BrowserResult CheckInChromium(const std::filesystem::path& html, const std::filesystem::path& work_dir,
                                     const std::string& fragment = "") {
  BrowserResult result;
  std::filesystem::create_directories(work_dir);
  const auto dom = work_dir / "dom.html", log = work_dir / "chromium.log", profile = work_dir / "profile";
  // The flags keep Chromium off the network entirely (the page must not need it); the virtual time
  // budget lets the page's scripts and plotly's rendering run to completion before the dump.
  const std::string command =
      "chromium --headless --no-sandbox --disable-gpu --disable-quic --no-first-run "
      "--disable-background-networking --disable-component-update --disable-sync --disable-dev-shm-usage "
      "--enable-logging=stderr --v=0 --virtual-time-budget=5000 --user-data-dir='" + profile.string() +
      "' --dump-dom 'file://" + std::filesystem::absolute(html).string() + fragment + "' > '" + dom.string() + "' 2> '" +
      log.string() + "'";
  if (std::system(command.c_str()) != 0) return result;
  const std::string text = ReadWhole(dom);
  result.ran = text.find("<body") != std::string::npos;
  std::smatch m;
  if (std::regex_search(text, m, std::regex("data-charts-expected=\"([0-9]+)\""))) result.expected = std::stoi(m[1]);
  if (std::regex_search(text, m, std::regex("data-charts-rendered=\"([0-9]+)\""))) result.rendered = std::stoi(m[1]);
  if (std::regex_search(text, m, std::regex("data-errors=\"([^\"]*)\""))) result.page_errors = m[1];
  if (std::regex_search(text, m, std::regex("data-export-svg=\"([0-9]+)\""))) result.exported_svg = std::stoi(m[1]);
  if (std::regex_search(text, m, std::regex("data-export-png=\"([0-9]+)\""))) result.exported_png = std::stoi(m[1]);
  // A rendered plotly chart holds an <svg class="main-svg"> (2D and 3D alike).
  for (size_t at = text.find("data-rendered=\"1\""); at != std::string::npos; at = text.find("data-rendered=\"1\"", at + 1))
    ++result.rendered_divs;
  std::istringstream lines(ReadWhole(log));
  for (std::string line; std::getline(lines, line);) {
    const bool console = line.find(":CONSOLE") != std::string::npos;
    if ((console && (line.find("ERROR") != std::string::npos || line.find("Error") != std::string::npos)) ||
        line.find("Uncaught") != std::string::npos)
      result.console_errors += line + "\n";
  }
  return result;
}

inline bool ChromiumAvailable() { return std::system("command -v chromium > /dev/null 2>&1") == 0; }

/// In CI (CI set, as `.ci/run` runs) the README's test command installs Chromium, so its absence is
/// a failure there; outside CI a developer who built by hand may skip the browser check.
inline bool BrowserCheckMayBeSkipped() { return std::getenv("CI") == nullptr; }

}  // namespace ema::test
