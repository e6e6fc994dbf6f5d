#include "cli.hpp"

namespace ema {

int RunSimulate(const std::vector<std::string>& /*args*/) { return cli::NotBuiltYet("simulate", "issue 6"); }

}  // namespace ema
