// ema pick — pick poles by hand on the stabilisation diagram in the browser, and watch the fit
// follow (docs/pick.md). Parsing here; the session in app/pick/pick_session.*, the server in
// app/pick/pick_server.*, the page in app/pick/pick.html and pick.js.
#include <iostream>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "cli.hpp"
#include "ema/core/error.hpp"
#include "ema/formats/io.hpp"
#include "pick/pick_server.hpp"
#include "pick/pick_session.hpp"
#include "stages.hpp"

namespace ema {

namespace {

const char* const kPickUsage =
    "ema pick FRF.unv [-o MODES.unv] [--json MODES.json] [--band LO:HI] [--order-max N] [--select F1,F2,...]\n"
    "         [--port P] [--no-browser] [any other ema fit option]";

}  // namespace

std::optional<app::PickConfig> app::ParsePickArgs(const std::vector<std::string>& args) {
  namespace po = cli::po;
  PickConfig config;
  PickOptions& options = config.options;
  po::options_description pick_options("ema pick: pick poles by hand in the browser (docs/pick.md); the server's options");
  pick_options.add_options()
      ("port", cli::Defaulted(&options.port), "TCP port on 127.0.0.1 (0: a free port)")
      ("no-browser", "do not open the page with xdg-open (only print its URL)");
  // The server's own options are taken out; everything else is `ema fit`'s command line.
  std::vector<std::string> fit_args;
  for (size_t k = 0; k < args.size(); ++k) {
    const std::string& a = args[k];
    if (a == "--help" || a == "-h") {
      // pick's usage and its server's options, then every `ema fit` option (pick takes them all).
      std::ostringstream head;
      head << kPickUsage << "\n\n" << pick_options;
      ParseFitArgs({"--help"}, /*require_input=*/false, {}, head.str());
      return std::nullopt;
    }
    if (a == "--no-browser") {
      options.open_browser = false;
    } else if (a == "--port" || a.rfind("--port=", 0) == 0) {
      std::string value = a.size() > 6 ? a.substr(7) : "";
      if (a == "--port") {
        if (k + 1 >= args.size()) throw UsageError("--port: expected a port number\nusage: " + std::string(kPickUsage));
        value = args[++k];
      }
      const double port = cli::ParseNumber(value, "--port");
      if (port != static_cast<int>(port)) throw UsageError("--port: expected a whole number, got '" + value + "'");
      options.port = static_cast<int>(port);
    } else {
      fit_args.push_back(a);
    }
  }
  // ema fit's parser, with ema pick's usage line in its messages.
  std::optional<FitConfig> fit = ParseFitArgs(fit_args, /*require_input=*/false, {}, kPickUsage);
  if (!fit) return std::nullopt;
  config.fit = std::move(*fit);
  if (config.fit.input.empty()) throw UsageError("the FRF file is required\nusage: " + std::string(kPickUsage));
  if (config.fit.options.method != curvefit::FitMethod::kPolymax)
    throw UsageError("--method peak: ema pick picks poles on the PolyMAX stabilisation diagram (--method polymax)");
  if (config.fit.output.empty())
    for (const std::string* path : {&config.fit.json_path, &config.fit.stabilisation_path, &config.fit.plot_path})
      if (!path->empty()) throw UsageError("--json, --stabilisation and --plot need -o MODES.unv (Save writes them all, as ema fit does)");
  if (std::string why; !options.IsValid(&why)) throw UsageError(why);
  return config;
}

int RunPick(const std::vector<std::string>& args) {
  const std::optional<app::PickConfig> config = app::ParsePickArgs(args);
  if (!config) return 0;
  const FrfSet frfs = formats::ReadFrfSet(config->fit.input);
  app::PickSession session(config->fit, frfs, config->options);
  std::cout << session.Summary() << std::flush;
  app::ServePick(session, config->options, std::cout);  // Done and Ctrl-C both end it cleanly
  return 0;
}

}  // namespace ema
