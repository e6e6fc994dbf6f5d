// `ema pick`'s local HTTP server (cpp-httplib): one page and a small JSON API over a PickSession.
//
// Security model (docs/pick.md): it listens on 127.0.0.1 only; every request must carry the
// session's random token (?token= or the X-Ema-Token header) and a Host header naming
// 127.0.0.1:PORT or localhost:PORT (no DNS rebinding), else 403; request bodies above
// PickOptions::max_body_bytes are refused (413); a malformed or refused pick is 400 and changes
// nothing. The only files written are the outputs of the command line (PickSession::Save).
#pragma once

#include <iosfwd>
#include <string>

#include "pick/pick_session.hpp"

namespace ema::app {

/// `bytes` random bytes from /dev/urandom as lower-case hex (InputError when it cannot be read).
std::string RandomHexToken(int bytes = 32);

/// True when `host` (a Host header) names this server: 127.0.0.1:PORT or localhost:PORT.
bool IsOwnHost(const std::string& host, int port);

/// Serves `session` until the page's Done or SIGINT/SIGTERM, then returns 0 after Done and the
/// signal's number after a signal (`ema pick` exits 0 either way; `ema run` stops). Prints "open URL"
/// (flushed) on `out` once listening, opens it with xdg-open when options.open_browser and a
/// display is present, and prints each Save's table and equivalent `ema fit` command on `out`.
/// InputError when the port cannot be bound.
int ServePick(PickSession& session, const PickOptions& options, std::ostream& out);

}  // namespace ema::app
