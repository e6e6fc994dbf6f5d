// Output files are written to a temporary file beside the target and renamed into place, so a
// failed run never leaves a half-written result (cli.md).
#pragma once

#include <filesystem>
#include <functional>
#include <ostream>

namespace ema::formats {

/// Writes `path` through `write` (binary-mode stream) into "<path>.tmp-XXXX" and renames it to
/// `path` once `write` returned and the stream flushed without error. On any exception the
/// temporary file is removed and the exception propagates; an existing `path` is left untouched.
void WriteFileAtomically(const std::filesystem::path& path,
                         const std::function<void(std::ostream&)>& write);

/// Text convenience wrapper of WriteFileAtomically.
void WriteTextFileAtomically(const std::filesystem::path& path, const std::string& text);

}  // namespace ema::formats
