#include "cli.hpp"

namespace ema {

int RunInfo(const std::vector<std::string>& /*args*/) { return cli::NotBuiltYet("info", "issue 2"); }

}  // namespace ema
