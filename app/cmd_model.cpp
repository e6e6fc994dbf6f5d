#include "cli.hpp"

namespace ema {

int RunModel(const std::vector<std::string>& /*args*/) { return cli::NotBuiltYet("model", "issue 6"); }

}  // namespace ema
