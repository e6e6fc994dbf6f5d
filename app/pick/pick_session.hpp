// `ema pick`: the state of one hand-picking session, without any HTTP (docs/pick.md).
//
// The session holds the FRFs and the `ema fit` configuration of the command line. Every pick is
// a call of curvefit::Fit with FitOptions::select_frequencies_hz = the picked frequencies — what
// `ema fit --select F1,F2,...` runs — and Save is app::RunFitStage itself with those
// frequencies, so the files written are those of the equivalent `ema fit` command by
// construction. The stabilisation diagram does not depend on the selection: it is computed once.
#pragma once

#include <chrono>
#include <cstddef>
#include <iosfwd>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "ema/core/types.hpp"
#include "ema/curvefit/fit.hpp"
#include "stages.hpp"

namespace ema::app {

/// What `ema pick` adds to `ema fit`'s options (defaults as `ema pick` uses them).
struct PickOptions {
  int port = 0;                             ///< --port; 0: a free port the system chooses
  bool open_browser = true;                 ///< --no-browser: false (also off without a display)
  std::size_t max_body_bytes = 64 * 1024;   ///< request bodies above this are refused (413)
  std::size_t max_picked = 256;             ///< more frequencies in one pick are refused (400)
  int max_display_frfs = 300;               ///< FRFs offered in the page's selector (driving points first)
  int max_display_lines = 1500;             ///< points per FRF curve (lines strided above this)

  /// Ceres style: false with the violated condition in *why.
  bool IsValid(std::string* why) const {
    if (port < 0 || port > 65535) return *why = "--port: expected 0 (any free port) or 1..65535", false;
    if (max_body_bytes < 1024) return *why = "max_body_bytes must be at least 1 KiB", false;
    if (max_picked < 1 || max_display_frfs < 1 || max_display_lines < 10)
      return *why = "max_picked, max_display_frfs and max_display_lines must be positive", false;
    return true;
  }
};

/// `ema pick`'s command line: the fit as `ema fit` parses it, plus the server's options.
struct PickConfig {
  FitConfig fit;       ///< fit.options.select_frequencies_hz: the first pick (empty = automatic)
  PickOptions options;
};

/// nullopt when --help was given (usage printed). UsageError for a bad command line, as
/// ParseFitArgs (every `ema fit` option is accepted; -o is optional: without it Save writes nothing).
std::optional<PickConfig> ParsePickArgs(const std::vector<std::string>& args);

/// A pick the session refuses (HTTP 400): what() says why; the session is unchanged.
class PickRequestError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// One picking session. Thread-safe: every member locks the session.
class PickSession {
 public:
  /// Runs the first fit (automatic selection, or config.fit's --select). Throws InputError as
  /// `ema fit` does for bad data; a first fit that finds no mode is kept (the user picks by hand).
  PickSession(FitConfig config, FrfSet frfs, PickOptions options = {});

  /// Everything the page draws: {"fixed": the diagram, mode indicators, measured FRFs, outputs;
  /// "state": StateJson()}.
  nlohmann::json DataJson() const;
  /// The current pick: modes (f ± σ, ζ ± σ, MPC, MPD, the pole behind each), MAC, synthesised FRFs,
  /// the equivalent `ema fit` command.
  nlohmann::json StateJson() const;

  /// {"frequencies_hz": [F1, ...]} (a hand pick; [] = nothing picked) or {"selection": "auto"}.
  /// Refits and returns StateJson(). PickRequestError (nothing changed) for a malformed request,
  /// a frequency that is not a positive number inside the band, two frequencies that pick the same
  /// pole, or a fit that fails on them.
  nlohmann::json Select(const nlohmann::json& request);

  /// Writes the outputs named on the command line exactly as `ema fit` (RunFitStage) with the
  /// current pick, prints its table and the equivalent command to `out`, and returns {"written":
  /// [paths], "command", "text"}. PickRequestError when there is no -o or nothing is picked.
  nlohmann::json Save(std::ostream& out);

  /// `ema fit INPUT [the fit options] [--select F1,F2,...] [-o ...] [--json ...]` of the current
  /// pick, frequencies in the shortest text that reads back as the same double.
  std::string EquivalentCommand() const;

  /// The current pick as `ema fit --select` takes it: "auto" for the automatic selection, else
  /// F1,F2,... (the exact doubles); "" when nothing is picked.
  std::string SelectText() const;
  /// The same as numbers: empty for the automatic selection, nullopt when nothing is picked.
  std::optional<std::vector<double>> Selection() const;

  /// The first fit's summary lines, as `ema pick` prints them before serving.
  std::string Summary() const;

 private:
  struct Pick {
    bool automatic = true;                 ///< automatic selection (no --select)
    std::vector<double> requested_hz;      ///< the given frequencies, ascending (hand pick)
    std::optional<curvefit::FitResult> fit;  ///< empty: nothing picked
    double fit_seconds = 0.0;
  };
  Pick FitPick(bool automatic, std::vector<double> requested_hz) const;
  nlohmann::json StateJsonLocked() const;
  std::string EquivalentCommandLocked() const;
  std::string SelectTextLocked() const;

  mutable std::mutex mutex_;
  FitConfig config_;
  FrfSet frfs_;
  PickOptions options_;
  curvefit::StabilisationDiagram diagram_;  ///< of the first fit; the same for every selection
  std::vector<int> display_lines_;          ///< FRF lines drawn
  std::vector<std::pair<int, int>> display_frfs_;  ///< (reference, output) drawn, driving points first
  Pick pick_;
  int saves_ = 0;
};

}  // namespace ema::app
