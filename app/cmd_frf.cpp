#include "cli.hpp"

namespace ema {

int RunFrf(const std::vector<std::string>& /*args*/) { return cli::NotBuiltYet("frf", "issue 3"); }

}  // namespace ema
