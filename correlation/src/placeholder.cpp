// Placeholder so the static library has a translation unit; remove once real sources exist.
namespace ema::correlation {
const char* ModuleName() { return "correlation"; }
}  // namespace ema::correlation
