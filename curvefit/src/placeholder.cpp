// Placeholder so the static library has a translation unit; remove once real sources exist.
namespace ema::curvefit {
const char* ModuleName() { return "curvefit"; }
}  // namespace ema::curvefit
