#include "cli.hpp"

namespace ema {

int RunRun(const std::vector<std::string>& /*args*/) { return cli::NotBuiltYet("run", "issue 8"); }

}  // namespace ema
