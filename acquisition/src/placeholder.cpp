// Placeholder so the static library has a translation unit; remove once real sources exist.
namespace ema::acquisition {
const char* ModuleName() { return "acquisition"; }
}  // namespace ema::acquisition
