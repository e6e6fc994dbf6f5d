// `ema pick`'s server: routes, the token/Host/body checks, the signal watcher, the browser.
#include "pick/pick_server.hpp"

#include <fcntl.h>
#include <httplib.h>
#include <pthread.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <mutex>
#include <thread>

#include "ema/core/error.hpp"
#include "pick/pick_page.hpp"

extern char** environ;

namespace ema::app {

namespace {

using json = nlohmann::json;

// Equal length and bytes, in time independent of where they differ.
bool SameSecret(const std::string& a, const std::string& b) {
  if (a.size() != b.size()) return false;
  unsigned char diff = 0;
  for (size_t i = 0; i < a.size(); ++i) diff |= static_cast<unsigned char>(a[i] ^ b[i]);
  return diff == 0;
}

void SendError(httplib::Response& res, int status, const std::string& message) {
  res.status = status;
  res.set_content(json{{"error", message}}.dump(), "application/json");
}

// xdg-open when a desktop is there to show the page: never waits for it, never lets it write to
// our terminal, and gives it the default signal mask (ours blocks SIGINT while serving).
pid_t OpenInBrowser(const std::string& url) {
  const char* display = std::getenv("DISPLAY");
  const char* wayland = std::getenv("WAYLAND_DISPLAY");
  if ((!display || !*display) && (!wayland || !*wayland)) return -1;
  if (std::system("command -v xdg-open > /dev/null 2>&1") != 0) return -1;
  posix_spawn_file_actions_t actions;
  posix_spawnattr_t attributes;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 2, "/dev/null", O_WRONLY, 0);
  posix_spawnattr_init(&attributes);
  sigset_t none;
  sigemptyset(&none);
  posix_spawnattr_setsigmask(&attributes, &none);
  posix_spawnattr_setflags(&attributes, POSIX_SPAWN_SETSIGMASK);
  pid_t pid = -1;
  const std::string program = "xdg-open";
  char* argv[] = {const_cast<char*>(program.c_str()), const_cast<char*>(url.c_str()), nullptr};
  if (posix_spawnp(&pid, "xdg-open", &actions, &attributes, argv, environ) != 0) pid = -1;
  posix_spawn_file_actions_destroy(&actions);
  posix_spawnattr_destroy(&attributes);
  return pid;
}

// A stop signal delivered to a thread that does not block it: the BLAS library's worker threads
// (OpenBLAS makes its pool when it is loaded, before serving blocks the signals in this process's
// threads) would otherwise take Ctrl-C by its default action and kill `ema pick` mid-write. The
// handler only records it (a lock-free atomic is async-signal-safe); the watcher acts on it.
std::atomic<int> stray_stop_signal{0};
void RecordStopSignal(int signal) { stray_stop_signal.store(signal); }

}  // namespace

std::string RandomHexToken(int bytes) {
  std::ifstream random("/dev/urandom", std::ios::binary);
  std::string raw(static_cast<size_t>(bytes), '\0');
  if (!random.read(raw.data(), bytes)) throw InputError("/dev/urandom", "cannot read the session token's random bytes");
  static const char kHex[] = "0123456789abcdef";
  std::string token;
  for (char c : raw) {
    const auto u = static_cast<unsigned char>(c);
    token += kHex[u >> 4];
    token += kHex[u & 15];
  }
  return token;
}

bool IsOwnHost(const std::string& host, int port) {
  std::string lower;
  for (char c : host) lower += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  // Built by append: GCC 12 warns (-Wrestrict, a false positive) on "literal" + std::string.
  const std::string suffix = std::string(":").append(std::to_string(port));
  return lower == std::string("127.0.0.1").append(suffix) || lower == std::string("localhost").append(suffix);
}

int ServePick(PickSession& session, const PickOptions& options, std::ostream& out) {
  const std::string token = RandomHexToken();
  const std::string page = PickPageHtml();
  std::mutex out_mutex;  // handlers run on the server's threads
  httplib::Server server;
  // httplib holds a thread per open connection for its keep-alive time; a browser keeps up to six
  // per host open, and a request that finds every thread taken waits for one to time out.
  server.new_task_queue = [] { return new httplib::ThreadPool(12); };
  server.set_payload_max_length(options.max_body_bytes);              // larger bodies: 413
  server.set_keep_alive_timeout(1);                                   // Done/Ctrl-C end within ~1 s

  const int port = options.port > 0 ? (server.bind_to_port("127.0.0.1", options.port) ? options.port : -1)
                                    : server.bind_to_any_port("127.0.0.1");
  if (port <= 0)
    throw InputError("--port " + std::to_string(options.port), "cannot listen on 127.0.0.1 (is the port in use?)");
  const std::string origin = "http://127.0.0.1:" + std::to_string(port);

  server.set_default_headers({
      {"Cache-Control", "no-store"},
      {"X-Content-Type-Options", "nosniff"},
      {"Referrer-Policy", "no-referrer"},  // the token is in the page's URL
      {"X-Frame-Options", "DENY"},
      {"Content-Security-Policy",
       "default-src 'none'; script-src 'unsafe-inline'; style-src 'unsafe-inline'; img-src data: blob:; "
       "connect-src 'self'; font-src data:; frame-ancestors 'none'; form-action 'none'; base-uri 'none'"},
  });
  // Before any route and before a body is read: the Host header (DNS rebinding), the token, and
  // for a POST from a browser its Origin.
  server.set_pre_routing_handler([&](const httplib::Request& req, httplib::Response& res) {
    if (!IsOwnHost(req.get_header_value("Host"), port)) {
      SendError(res, 403, "forbidden: the Host header must be 127.0.0.1:" + std::to_string(port) + " or localhost:" +
                              std::to_string(port));
      return httplib::Server::HandlerResponse::Handled;
    }
    const std::string given = req.has_param("token") ? req.get_param_value("token") : req.get_header_value("X-Ema-Token");
    if (!SameSecret(given, token)) {
      SendError(res, 403, "forbidden: this server answers only requests that carry its token");
      return httplib::Server::HandlerResponse::Handled;
    }
    const std::string request_origin = req.get_header_value("Origin");
    if (req.method == "POST" && !request_origin.empty() && request_origin != origin &&
        request_origin != "http://localhost:" + std::to_string(port)) {
      SendError(res, 403, "forbidden: a request from another site (Origin " + request_origin + ")");
      return httplib::Server::HandlerResponse::Handled;
    }
    // No compression: Debian's httplib would brotli-compress every answer a browser accepts so
    // (seconds for the 4.8 MB page, ~0.6 s per pick), far more than the loopback saves. The
    // request is httplib's own non-const object, handed to this handler as const.
    const_cast<httplib::Request&>(req).headers.erase("Accept-Encoding");
    return httplib::Server::HandlerResponse::Unhandled;
  });
  server.set_error_handler([](const httplib::Request&, httplib::Response& res) {
    if (!res.body.empty()) return;
    if (res.status == 413) SendError(res, 413, "request body too large");
    else if (res.status == 404) SendError(res, 404, "no such page");
    else if (res.status == 400)  // httplib refuses it before any handler: a POST without Content-Length, ...
      SendError(res, 400, "malformed HTTP request (a POST without a body needs Content-Length: 0, e.g. curl -d '')");
    else SendError(res, res.status, "request refused");
  });

  server.Get("/", [&](const httplib::Request&, httplib::Response& res) { res.set_content(page, "text/html; charset=utf-8"); });
  server.Get("/api/data", [&](const httplib::Request&, httplib::Response& res) {
    res.set_content(session.DataJson().dump(), "application/json");
  });
  server.Post("/api/select", [&](const httplib::Request& req, httplib::Response& res) {
    json request;
    try {
      request = json::parse(req.body);
    } catch (const json::exception& e) {  // a syntax error, or a number beyond a double (1e400)
      return SendError(res, 400, std::string("malformed JSON: ") + e.what());
    }
    try {
      const auto t0 = std::chrono::steady_clock::now();
      json state = session.Select(request);
      const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      state["server_seconds"] = seconds;
      std::string picked;
      for (const json& f : state["picked_hz"]) picked += (picked.empty() ? "" : ", ") + ExactNumberText(f.get<double>());
      {
        std::lock_guard<std::mutex> lock(out_mutex);
        out << "pick: " << state["selection"].get<std::string>() << (picked.empty() ? "" : " " + picked + " Hz") << " -> "
            << state["modes"].size() << " mode(s) in " << static_cast<int>(seconds * 1000 + 0.5) << " ms" << std::endl;
      }
      res.set_content(state.dump(), "application/json");
    } catch (const PickRequestError& e) {
      SendError(res, 400, e.what());
    } catch (const std::exception& e) {
      SendError(res, 500, e.what());
    }
  });
  server.Post("/api/save", [&](const httplib::Request&, httplib::Response& res) {
    try {
      std::lock_guard<std::mutex> lock(out_mutex);
      json saved = session.Save(out);
      saved["state"] = session.StateJson();
      res.set_content(saved.dump(), "application/json");
    } catch (const PickRequestError& e) {
      SendError(res, 400, e.what());
    } catch (const std::exception& e) {
      SendError(res, 500, e.what());
    }
  });
  std::atomic<bool> done{false};
  server.Post("/api/done", [&](const httplib::Request&, httplib::Response& res) {
    res.set_content(json{{"done", true}}.dump(), "application/json");
    done = true;
    server.stop();  // the listening loop returns once this response is written
  });

  // SIGINT/SIGTERM are blocked on every thread while serving and taken by a watcher thread, which
  // stops the server: Ctrl-C ends `ema pick` as Done does (exit 0), never in a handler's middle.
  // Threads made before (a BLAS pool) do not block them: there a handler records the signal.
  sigset_t stop_signals, previous;
  sigemptyset(&stop_signals);
  sigaddset(&stop_signals, SIGINT);
  sigaddset(&stop_signals, SIGTERM);
  struct sigaction record = {}, previous_int = {}, previous_term = {};
  record.sa_handler = RecordStopSignal;
  sigemptyset(&record.sa_mask);
  stray_stop_signal = 0;
  sigaction(SIGINT, &record, &previous_int);
  sigaction(SIGTERM, &record, &previous_term);
  pthread_sigmask(SIG_BLOCK, &stop_signals, &previous);
  std::atomic<bool> serving{true};
  int caught = 0;
  std::thread watcher([&] {
    const timespec tick = {0, 200 * 1000 * 1000};
    while (serving) {
      int signal = sigtimedwait(&stop_signals, nullptr, &tick);
      if (signal <= 0) signal = stray_stop_signal.exchange(0);
      if (signal <= 0) continue;
      caught = signal;
      // Repeated until the loop has ended: a signal may come before listening has begun.
      while (serving) {
        server.stop();
        std::this_thread::sleep_for(std::chrono::milliseconds(50));
      }
    }
  });

  const std::string url = origin + "/?token=" + token;
  out << "open " << url << "\n(the page's Done button or Ctrl-C ends ema pick)" << std::endl;
  const pid_t browser = options.open_browser ? OpenInBrowser(url) : -1;
  const bool listened = server.listen_after_bind();
  serving = false;
  watcher.join();
  // A signal that arrived after the watcher stopped is dropped, not delivered on unblocking.
  sigset_t pending;
  sigpending(&pending);
  for (int s : {SIGINT, SIGTERM})
    if (sigismember(&pending, s)) {
      const timespec now = {0, 0};
      sigset_t one;
      sigemptyset(&one);
      sigaddset(&one, s);
      sigtimedwait(&one, nullptr, &now);
      caught = s;
    }
  if (const int stray = stray_stop_signal.exchange(0); stray > 0) caught = stray;
  pthread_sigmask(SIG_SETMASK, &previous, nullptr);
  sigaction(SIGINT, &previous_int, nullptr);
  sigaction(SIGTERM, &previous_term, nullptr);
  if (browser > 0) waitpid(browser, nullptr, WNOHANG);  // reaped if it is done; never waited for
  if (!listened && !done && !caught) throw InputError(url, "the server stopped unexpectedly");
  out << "ema pick: " << (done ? "done" : caught == SIGTERM ? "stopped (SIGTERM)" : "stopped (Ctrl-C)") << std::endl;
  return done ? 0 : caught;
}

}  // namespace ema::app
