#include "ema/formats/referenced_files.hpp"

#include <set>
#include <string>
#include <system_error>
#include <toml++/toml.h>

namespace ema::formats {
namespace fs = std::filesystem;

namespace {

constexpr int kMaxDepth = 8;  // a project names a model that names curves: depth 2 in practice

void Collect(const fs::path& file, int depth, std::set<fs::path>* seen, std::vector<fs::path>* out) {
  std::error_code ec;
  if (depth > kMaxDepth || fs::file_size(file, ec) > (16u << 20) || ec) return;  // TOML files are small
  toml::table root;
  try {
    root = toml::parse_file(file.string());
  } catch (const std::exception&) {
    return;
  }
  const fs::path dir = file.parent_path();
  auto visit = [&](const toml::node& node, auto&& self) -> void {
    if (const auto* t = node.as_table()) {
      for (const auto& [key, value] : *t) self(value, self);
    } else if (const auto* a = node.as_array()) {
      for (const auto& value : *a) self(value, self);
    } else if (const auto* s = node.as_string()) {
      const std::string& text = s->get();
      if (text.empty() || text.size() > 4096) return;
      fs::path p(text);
      if (p.is_relative()) p = dir / p;
      std::error_code e;
      if (!fs::is_regular_file(p, e)) return;
      const fs::path canonical = fs::weakly_canonical(p, e);
      if (e || !seen->insert(canonical).second) return;
      out->push_back(p);
      if (p.extension() == ".toml") Collect(p, depth + 1, seen, out);
    }
  };
  visit(root, visit);
}

}  // namespace

std::vector<fs::path> FilesNamedIn(const fs::path& path) {
  std::set<fs::path> seen;
  std::error_code ec;
  seen.insert(fs::weakly_canonical(path, ec));
  std::vector<fs::path> out;
  Collect(path, 0, &seen, &out);
  return out;
}

}  // namespace ema::formats
