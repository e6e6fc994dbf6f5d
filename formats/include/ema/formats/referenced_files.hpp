// Which files a TOML file (model, test plan, project) names, so that a command can refuse an
// output that would replace one of them (../shared/spec/cli.md "outputs never replace inputs").
#pragma once

#include <filesystem>
#include <vector>

namespace ema::formats {

/// Every existing regular file named by a string value anywhere in the TOML file `path`
/// (relative values resolved against the file's folder), and, for each named `.toml` file, the
/// files it names in turn. A tolerant scan, not a check: a file that cannot be read or parsed
/// names nothing (its own reader reports the error later). The result excludes `path` itself.
std::vector<std::filesystem::path> FilesNamedIn(const std::filesystem::path& path);

}  // namespace ema::formats
