// Placeholder so the static library has a translation unit; remove once real sources exist.
namespace ema::frf {
const char* ModuleName() { return "frf"; }
}  // namespace ema::frf
