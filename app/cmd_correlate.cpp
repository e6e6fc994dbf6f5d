#include "cli.hpp"

namespace ema {

int RunCorrelate(const std::vector<std::string>& /*args*/) { return cli::NotBuiltYet("correlate", "issue 5"); }

}  // namespace ema
