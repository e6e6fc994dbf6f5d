#include "ema/formats/output_guard.hpp"

#include <cstddef>
#include <filesystem>
#include <system_error>
#include <utility>

#include "ema/core/error.hpp"
#include "ema/formats/referenced_files.hpp"

namespace ema::formats {

namespace fs = std::filesystem;

namespace {

// True when `a` and `b` name the same file: by identity when both exist (symlinks, hard links),
// else by their absolute paths with `.`, `..` and existing symlinks resolved.
bool SameFile(const fs::path& a, const fs::path& b) {
  std::error_code ec;
  if (fs::exists(a, ec) && fs::exists(b, ec)) {
    const bool same = fs::equivalent(a, b, ec);
    if (!ec) return same;
  }
  const fs::path ca = fs::weakly_canonical(fs::absolute(a, ec), ec);
  const fs::path cb = fs::weakly_canonical(fs::absolute(b, ec), ec);
  return ca == cb;
}

std::string NamedPathArg(const PathArg& p) {
  const bool positional = p.option.empty() || p.option[0] != '-';
  return (positional ? std::string() : p.option + " ") + p.path;
}

}  // namespace

void RefuseOutputsOverInputs(const std::vector<PathArg>& inputs, const std::vector<PathArg>& outputs) {
  // Expand the inputs: files named by TOML inputs, files in input folders.
  std::vector<std::pair<PathArg, fs::path>> all;  // (as given, the file)
  for (const PathArg& in : inputs) {
    if (in.path.empty()) continue;
    std::error_code ec;
    all.emplace_back(in, fs::path(in.path));
    if (fs::is_directory(in.path, ec)) {
      for (const auto& entry : fs::directory_iterator(in.path, ec))
        if (entry.is_regular_file(ec)) all.emplace_back(in, entry.path());
    } else if (fs::path(in.path).extension() == ".toml") {
      for (const fs::path& f : FilesNamedIn(in.path)) all.emplace_back(in, f);
    }
  }
  for (std::size_t i = 0; i < outputs.size(); ++i) {
    const PathArg& out = outputs[i];
    if (out.path.empty()) continue;
    for (const auto& [in, file] : all) {
      if (!SameFile(out.path, file)) continue;
      // Built by append: GCC 12 warns (-Wrestrict, a false positive) on "literal" + std::string&&.
      std::string message = NamedPathArg(out);
      message.append(": refused, it would replace ");
      if (file != fs::path(in.path)) message.append("'").append(file.string()).append("', which the input ");
      else message.append("the input ");
      message.append(NamedPathArg(in));
      if (file != fs::path(in.path)) message.append(" names");
      message.append(" (outputs never replace inputs: choose another output name)");
      throw UsageError(message);
    }
    for (std::size_t j = 0; j < i; ++j)
      if (!outputs[j].path.empty() && SameFile(out.path, outputs[j].path))
        throw UsageError(NamedPathArg(out) + ": refused, " + NamedPathArg(outputs[j]) + " writes the same file");
  }
}

}  // namespace ema::formats
