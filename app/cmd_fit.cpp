#include "cli.hpp"

namespace ema {

int RunFit(const std::vector<std::string>& /*args*/) { return cli::NotBuiltYet("fit", "issue 4"); }

}  // namespace ema
