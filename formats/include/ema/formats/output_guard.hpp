// cli.md "Every command: outputs never replace inputs": the one check every command (and the
// Python package's writers) makes before anything is read or written (docs/reliability.md).
#pragma once

#include <string>
#include <vector>

namespace ema::formats {

/// A path a command reads or writes, with the option that named it (for messages).
struct PathArg {
  std::string option;  ///< e.g. "-o", "--json", "input"
  std::string path;
};

/// Throws UsageError (exit 2) naming both paths when an output resolves to one of the inputs, or
/// two outputs to one file; paths are compared after resolving `.`/`..`, relative paths and
/// symlinks (and hard links, by file identity). An input TOML file (model, plan, project) brings
/// the files it names (FilesNamedIn: curves, [fe] matrices, DOF maps, node lists, the project's
/// model and data); an input folder brings the files in it. An option that does not start with
/// '-' (a positional input) is left out of the message. Call at the top of a command, before
/// anything is read or written.
void RefuseOutputsOverInputs(const std::vector<PathArg>& inputs, const std::vector<PathArg>& outputs);

}  // namespace ema::formats
