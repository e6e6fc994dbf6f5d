#include "cli.hpp"

namespace ema {

int RunDiagnose(const std::vector<std::string>& /*args*/) { return cli::NotBuiltYet("diagnose", "issue 7"); }

}  // namespace ema
