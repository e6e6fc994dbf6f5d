// Placeholder so the static library has a translation unit; remove once real sources exist.
namespace ema::model {
const char* ModuleName() { return "model"; }
}  // namespace ema::model
