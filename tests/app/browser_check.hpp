// Loads an HTML file in headless Chromium (Debian's `chromium`) and reports what the page said:
// how many charts it expected and rendered (body data attributes set by app/report/report.js),
// the errors it caught, and every console error Chromium logged.
//
// ChromiumPage drives Chromium over the DevTools protocol instead (--remote-debugging-pipe:
// NUL-separated JSON messages on file descriptors 3 and 4), to emulate a CSS media type ("print")
// and a viewport, and to run a probe script in the loaded page: ReadScreen (the text a reader sees
// without scrolling, the tables) and CheckPrintLayout (no table or figure wider than the printable
// width) are built on it.
#pragma once

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "test_files.hpp"

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
  const std::string text = Slurp(dom);
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
  std::istringstream lines(Slurp(log));
  for (std::string line; std::getline(lines, line);) {
    const bool console = line.find(":CONSOLE") != std::string::npos;
    if ((console && (line.find("ERROR") != std::string::npos || line.find("Error") != std::string::npos)) ||
        line.find("Uncaught") != std::string::npos)
      result.console_errors += line + "\n";
  }
  return result;
}

/// A page in headless Chromium driven over the DevTools protocol (--remote-debugging-pipe): the CSS
/// media type and the viewport are emulated, probe scripts run in the page. Chromium is this
/// process's child; it is closed (and if need be stopped) when the object goes.
class ChromiumPage {
 public:
  using json = nlohmann::json;

  /// Starts Chromium, sets `media` ("screen" or "print") and a viewport of width × height CSS px
  /// without scrollbars, loads `html` and waits for its load event. False: see error().
  bool Open(const std::filesystem::path& html, const std::filesystem::path& work_dir, const std::string& media, int width,
            int height, int timeout_s = 90) {
    deadline_ = std::chrono::steady_clock::now() + std::chrono::seconds(timeout_s);
    std::filesystem::create_directories(work_dir);
    int to_chrome[2], from_chrome[2];
    if (pipe(to_chrome) != 0) return Fail("pipe failed");
    if (pipe(from_chrome) != 0) {
      close(to_chrome[0]), close(to_chrome[1]);
      return Fail("pipe failed");
    }
    const std::string profile = "--user-data-dir=" + (work_dir / "profile-cdp").string();
    const std::string log = (work_dir / "chromium-cdp.log").string();
    pid_ = fork();
    if (pid_ == 0) {
      // Chromium reads commands from fd 3 and writes replies to fd 4.
      const int in = fcntl(to_chrome[0], F_DUPFD, 10), out = fcntl(from_chrome[1], F_DUPFD, 10);
      dup2(in, 3);
      dup2(out, 4);
      const int log_fd = open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      if (log_fd >= 0) dup2(log_fd, 1), dup2(log_fd, 2);
      for (int fd = 5; fd < 1024; ++fd) close(fd);
      execlp("chromium", "chromium", "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
             "--disable-background-networking", "--disable-component-update", "--disable-sync",
             "--disable-dev-shm-usage", "--hide-scrollbars", "--remote-debugging-pipe", profile.c_str(), "about:blank",
             static_cast<char*>(nullptr));
      _exit(127);
    }
    close(to_chrome[0]);
    close(from_chrome[1]);
    writer_ = to_chrome[1];
    reader_ = from_chrome[0];
    if (pid_ < 0) return Fail("fork failed");
    struct sigaction ignore = {};
    ignore.sa_handler = SIG_IGN;
    sigaction(SIGPIPE, &ignore, &previous_sigpipe_);  // a Chromium that died must not kill the test
    sigpipe_saved_ = true;
    const json targets = Call("Target.getTargets", json::object(), false);
    std::string target;
    if (targets.contains("result"))
      for (const json& t : targets["result"]["targetInfos"])
        if (t.value("type", "") == "page") target = t.value("targetId", "");
    if (target.empty()) return Fail("no page target: " + targets.dump());
    const json attached = Call("Target.attachToTarget", {{"targetId", target}, {"flatten", true}}, false);
    session_ = attached.contains("result") ? attached["result"].value("sessionId", "") : "";
    if (session_.empty()) return Fail("cannot attach: " + attached.dump());
    Call("Runtime.enable", json::object());
    Call("Page.enable", json::object());
    if (!Emulate(media, width, height)) return false;
    const json navigated = Call("Page.navigate", {{"url", "file://" + std::filesystem::absolute(html).string()}});
    if (!navigated.contains("result")) return Fail("cannot navigate: " + navigated.dump());
    if (Receive([](const json& m) { return m.value("method", "") == "Page.loadEventFired"; }).is_null())
      return Fail("the page did not load in time");
    return true;
  }

  /// Emulates another media type and viewport, as Chromium's print path changes both after the
  /// page's 'beforeprint' handlers ran.
  bool Emulate(const std::string& media, int width, int height) {
    for (const auto& [method, params] :
         {std::pair<std::string, json>{"Emulation.setEmulatedMedia", {{"media", media}}},
          {"Emulation.setDeviceMetricsOverride",
           {{"width", width}, {"height", height}, {"deviceScaleFactor", 1}, {"mobile", false}}},
          {"Emulation.setScrollbarsHidden", {{"hidden", true}}}})
      if (!Call(method, params).contains("result")) return Fail(method + " failed");
    return true;
  }

  /// Evaluates `expression` in the page (a promise is awaited); its value must be a JSON text,
  /// which is returned parsed. Discarded JSON: see error().
  json Evaluate(const std::string& expression) {
    const json evaluated =
        Call("Runtime.evaluate", {{"expression", expression}, {"returnByValue", true}, {"awaitPromise", true}});
    const json none = json::value_t::discarded;
    if (!evaluated.contains("result") || !evaluated["result"].contains("result"))
      return Fail("the probe failed: " + evaluated.dump()), none;
    const json& value = evaluated["result"]["result"];
    if (evaluated["result"].contains("exceptionDetails") || !value.contains("value") || !value["value"].is_string())
      return Fail("the probe failed: " + evaluated.dump()), none;
    json parsed = json::parse(value["value"].get<std::string>(), nullptr, false);
    if (parsed.is_discarded()) Fail("the probe returned no JSON");
    return parsed;
  }

  const std::string& error() const { return error_; }
  /// The page's uncaught exceptions so far (Runtime.exceptionThrown).
  const std::string& exceptions() const { return exceptions_; }

  ~ChromiumPage() {
    if (writer_ >= 0) {
      if (!session_.empty() || pid_ > 0) Send("Browser.close", json::object(), false);
      close(writer_);
    }
    if (reader_ >= 0) close(reader_);
    if (pid_ > 0) {
      // Chromium exits on Browser.close; if it has not within 10 s, it is stopped (our child).
      int status = 0;
      pid_t done = 0;
      for (int i = 0; i < 100 && (done = waitpid(pid_, &status, WNOHANG)) == 0; ++i)
        std::this_thread::sleep_for(std::chrono::milliseconds(100));
      if (done == 0) {
        kill(pid_, SIGKILL);
        waitpid(pid_, &status, 0);
      }
    }
    if (sigpipe_saved_) sigaction(SIGPIPE, &previous_sigpipe_, nullptr);
  }

 private:
  bool Fail(const std::string& why) {
    if (error_.empty()) error_ = why;
    return false;
  }
  int Send(const std::string& method, const json& params, bool in_session = true) {
    json message = {{"id", ++next_id_}, {"method", method}, {"params", params}};
    if (in_session && !session_.empty()) message["sessionId"] = session_;
    const std::string text = message.dump() + std::string(1, '\0');
    for (size_t done = 0; done < text.size();) {
      const ssize_t n = write(writer_, text.data() + done, text.size() - done);
      if (n <= 0) return -1;
      done += static_cast<size_t>(n);
    }
    return next_id_;
  }
  // Reads messages until one satisfies `wanted` (null after the deadline or when Chromium exited).
  template <typename Wanted>
  json Receive(const Wanted& wanted) {
    for (;;) {
      for (size_t end = buffer_.find('\0'); end != std::string::npos; end = buffer_.find('\0')) {
        json message = json::parse(buffer_.substr(0, end), nullptr, false);
        buffer_.erase(0, end + 1);
        if (message.is_discarded()) continue;
        if (message.value("method", "") == "Runtime.exceptionThrown")
          exceptions_ += message["params"]["exceptionDetails"].dump() + "\n";
        if (wanted(message)) return message;
      }
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline_ - std::chrono::steady_clock::now());
      if (left.count() <= 0) return json();
      pollfd fd = {reader_, POLLIN, 0};
      if (poll(&fd, 1, static_cast<int>(std::min<long long>(left.count(), 1000))) <= 0) continue;
      char chunk[65536];
      const ssize_t n = read(reader_, chunk, sizeof chunk);
      if (n <= 0) return json();
      buffer_.append(chunk, static_cast<size_t>(n));
    }
  }
  json Call(const std::string& method, const json& params, bool in_session = true) {
    const int id = Send(method, params, in_session);
    if (id < 0) return json();
    return Receive([id](const json& m) { return m.value("id", -1) == id; });
  }

  pid_t pid_ = -1;
  int writer_ = -1, reader_ = -1;
  int next_id_ = 0;
  std::string session_, buffer_, error_, exceptions_;
  std::chrono::steady_clock::time_point deadline_;
  struct sigaction previous_sigpipe_ = {};
  bool sigpipe_saved_ = false;
};

/// What a probe script evaluated in the page returned.
struct PageProbe {
  bool ran = false;           ///< Chromium started, the page loaded and the probe returned
  nlohmann::json value;       ///< the probe's value (the JSON text it returned, parsed)
  std::string error;          ///< why not, when !ran; and the page's uncaught exceptions
};

/// Opens `html` with the CSS media type `media` and a width × height viewport, then evaluates
/// `probe` (a JavaScript expression whose value, or promise of a value, is a JSON text).
inline PageProbe EvaluateInChromium(const std::filesystem::path& html, const std::filesystem::path& work_dir,
                                    const std::string& media, int width, int height, const std::string& probe) {
  PageProbe result;
  ChromiumPage page;
  if (page.Open(html, work_dir, media, width, height)) {
    result.value = page.Evaluate(probe);
    result.ran = !result.value.is_discarded();
  }
  result.error = page.error() + page.exceptions();
  return result;
}

/// The probe scripts below wait until the report has drawn every chart (its body's
/// data-charts-rendered equals data-charts-expected; 30 s at most), then measure.
inline const char* const kWaitForCharts = R"JS(
  new Promise(function (resolve) {
    var t0 = Date.now();
    (function wait() {
      var b = document.body, e = b.getAttribute('data-charts-expected');
      if ((e !== null && e === b.getAttribute('data-charts-rendered')) || Date.now() - t0 > 30000) resolve();
      else setTimeout(wait, 100);
    })();
  }))JS";

/// What a reader sees on the first screen (no scrolling) and the page's tables.
struct ScreenView {
  bool ran = false;
  std::string error;
  struct Text {
    std::string text;
    std::string color;        ///< computed CSS colour of its element ("rgb(r, g, b)")
    std::string font_family;
  };
  std::vector<Text> visible;  ///< text nodes wholly inside the viewport and not clipped by an overflow box
  struct Table {
    std::vector<std::string> headers;
    std::vector<std::vector<std::string>> rows;  ///< the body rows a reader sees (display not none)
  };
  std::vector<Table> tables;  ///< every table of the page, in order
  /// Every visible text joined by newlines.
  std::string VisibleText() const {
    std::string out;
    for (const Text& t : visible) out += t.text + "\n";
    return out;
  }
  /// The first visible text holding `needle`; nullptr when none does.
  const Text* Find(const std::string& needle) const {
    for (const Text& t : visible)
      if (t.text.find(needle) != std::string::npos) return &t;
    return nullptr;
  }
};

/// Opens `html` as a screen of width × height CSS px (1366 × 768 by default: a common laptop) and
/// reads what the reader sees before scrolling, and every table.
inline ScreenView ReadScreen(const std::filesystem::path& html, const std::filesystem::path& work_dir, int width = 1366,
                             int height = 768) {
  static const std::string probe = std::string("(") + kWaitForCharts + R"JS().then(function () {
    window.scrollTo(0, 0);
    var W = window.innerWidth, H = window.innerHeight, out = { visible: [], tables: [] };
    function inside(r, box) { return r.left >= box.left - 0.5 && r.right <= box.right + 0.5 && r.top >= box.top - 0.5 && r.bottom <= box.bottom + 0.5; }
    function seen(node) {
      var range = document.createRange();
      range.selectNodeContents(node);
      var rects = range.getClientRects();
      if (!rects.length) return false;
      for (var i = 0; i < rects.length; i++) {
        var r = rects[i];
        if (!inside(r, { left: 0, top: 0, right: W, bottom: H })) return false;
        for (var a = node.parentElement; a && a !== document.documentElement; a = a.parentElement) {
          var st = getComputedStyle(a);
          if (st.visibility === 'hidden' || st.opacity === '0') return false;
          if ((st.overflowX !== 'visible' || st.overflowY !== 'visible') && !inside(r, a.getBoundingClientRect())) return false;
        }
      }
      return true;
    }
    var walker = document.createTreeWalker(document.body, NodeFilter.SHOW_TEXT);
    for (var n = walker.nextNode(); n; n = walker.nextNode()) {
      if (!n.textContent.trim() || !n.parentElement || n.parentElement.closest('script,style,svg')) continue;
      if (!seen(n)) continue;
      var cs = getComputedStyle(n.parentElement);
      out.visible.push({ text: n.textContent, color: cs.color, font: cs.fontFamily });
    }
    document.querySelectorAll('table').forEach(function (t) {
      var rows = Array.prototype.slice.call(t.rows);
      var head = rows.length ? rows[0] : null;
      var table = { headers: head ? Array.prototype.map.call(head.cells, function (c) { return c.textContent; }) : [], rows: [] };
      rows.slice(1).forEach(function (r) {
        if (getComputedStyle(r).display === 'none') return;
        table.rows.push(Array.prototype.map.call(r.cells, function (c) { return c.textContent; }));
      });
      out.tables.push(table);
    });
    return JSON.stringify(out);
  }))JS";
  ScreenView view;
  const PageProbe p = EvaluateInChromium(html, work_dir, "screen", width, height, probe);
  view.ran = p.ran;
  view.error = p.error;
  if (!p.ran) return view;
  for (const auto& t : p.value["visible"])
    view.visible.push_back({t.value("text", ""), t.value("color", ""), t.value("font", "")});
  for (const auto& t : p.value["tables"]) {
    ScreenView::Table table;
    for (const auto& h : t["headers"]) table.headers.push_back(h.get<std::string>());
    for (const auto& r : t["rows"]) {
      std::vector<std::string> row;
      for (const auto& c : r) row.push_back(c.get<std::string>());
      table.rows.push_back(std::move(row));
    }
    view.tables.push_back(std::move(table));
  }
  return view;
}

/// The page laid out as Chromium prints it: print media, the printable width of the paper.
struct PrintLayout {
  bool ran = false;
  std::string error;
  bool print_media = false;          ///< the page saw `@media print` apply (matchMedia)
  int width = 0;                     ///< the layout width (CSS px)
  int page_scroll_width = 0;         ///< the document's width: more than `width` = cut off on paper
  int figures = 0;                   ///< tables, charts, images and preformatted blocks measured
  std::vector<std::string> too_wide; ///< each table or figure (or box) wider than the page, or cut off
};

/// Chromium's print path, emulated: the page is loaded on a 1366 × 768 screen and its charts drawn;
/// 'beforeprint' runs there (as Chromium runs it, with the window's layout); then, with no script
/// in between, the page is laid out with print media at the printable width of A4 portrait with
/// the report's 12 mm margins (186 mm = 703 CSS px at 96 px per inch) and every box is measured:
/// none may reach past the page's edges, and none may hide part of its content in an overflow
/// box (a scrolled table is cut off on paper).
inline PrintLayout CheckPrintLayout(const std::filesystem::path& html, const std::filesystem::path& work_dir,
                                    int width_px = 703, int height_px = 1000) {
  static const std::string before = std::string("(") + kWaitForCharts + R"JS().then(function () {
    var b = document.body, t0 = Date.now();
    return new Promise(function (resolve) {  // the 3D charts' print pictures, if the page makes them
      (function wait() {
        if (b.getAttribute('data-print-snapshots') || Date.now() - t0 > 20000) resolve(); else setTimeout(wait, 100);
      })();
    });
  }).then(function () {
    window.dispatchEvent(new Event('beforeprint'));
    return new Promise(function (resolve) { setTimeout(resolve, 1000); });
  }).then(function () {
    return JSON.stringify({ charts: document.body.getAttribute('data-charts-rendered') });
  }))JS";
  static const std::string measure = R"JS((function () {
    var W = document.documentElement.clientWidth;
    var out = { print_media: matchMedia('print').matches, width: W, page_scroll_width: document.documentElement.scrollWidth,
                figures: 0, too_wide: [] };
    var reported = [];
    function where(el) {
      var s = el.closest('section'), h = s ? s.querySelector('h2') : null;
      var cls = (el.getAttribute('class') || '').split(' ')[0];
      return el.tagName.toLowerCase() + (cls ? '.' + cls : '') + ' in "' + (h ? h.textContent.slice(0, 70) : 'the page') + '"';
    }
    var all = document.body.querySelectorAll('*');
    for (var i = 0; i < all.length; i++) {
      var el = all[i];
      if (el.tagName.toLowerCase() !== 'svg' && el.closest('svg')) continue;  // inside a figure: the figure counts
      if (reported.some(function (r) { return r.contains(el); })) continue;    // the outermost offender only
      var rc = el.getBoundingClientRect();
      if (rc.width === 0 || rc.height === 0 || rc.right <= 0) continue;        // not drawn (plotly's off-page helpers)
      var st = getComputedStyle(el);
      if (st.visibility === 'hidden' || st.position === 'fixed') continue;
      if (/^(TABLE|PRE|IMG|CANVAS)$/.test(el.tagName) || el.tagName.toLowerCase() === 'svg' ||
          el.classList.contains('js-plotly-plot')) out.figures++;
      if (rc.left < -1 || rc.right > W + 1) {
        out.too_wide.push(where(el) + ' spans ' + Math.round(rc.left) + '..' + Math.round(rc.right) + ' px');
        reported.push(el);
      } else if (st.overflowX !== 'visible' && el.scrollWidth > el.clientWidth + 1) {
        out.too_wide.push(where(el) + ' cuts off ' + (el.scrollWidth - el.clientWidth) + ' px of its content');
        reported.push(el);
      }
    }
    return JSON.stringify(out);
  })())JS";
  PrintLayout layout;
  ChromiumPage page;
  if (page.Open(html, work_dir, "screen", 1366, 768) && !page.Evaluate(before).is_discarded() &&
      page.Emulate("print", width_px, height_px)) {
    const nlohmann::json value = page.Evaluate(measure);
    if (!value.is_discarded()) {
      layout.ran = true;
      layout.print_media = value.value("print_media", false);
      layout.width = value.value("width", 0);
      layout.page_scroll_width = value.value("page_scroll_width", 0);
      layout.figures = value.value("figures", 0);
      for (const auto& t : value["too_wide"]) layout.too_wide.push_back(t.get<std::string>());
    }
  }
  layout.error = page.error() + page.exceptions();
  return layout;
}

inline bool ChromiumAvailable() { return std::system("command -v chromium > /dev/null 2>&1") == 0; }

/// In CI (CI set, as `.ci/run` runs) the README's test command installs Chromium, so its absence is
/// a failure there; outside CI a developer who built by hand may skip the browser check.
inline bool BrowserCheckMayBeSkipped() { return std::getenv("CI") == nullptr; }

}  // namespace ema::test
