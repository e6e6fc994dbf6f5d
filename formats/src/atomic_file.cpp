#include "ema/formats/atomic_file.hpp"

#include <fstream>
#include <random>
#include <string>

#include "ema/core/error.hpp"

namespace ema::formats {

void WriteFileAtomically(const std::filesystem::path& path,
                         const std::function<void(std::ostream&)>& write) {
  namespace fs = std::filesystem;
  std::random_device seed;
  const fs::path tmp = path.string() + ".tmp-" + std::to_string(seed() % 1000000);
  try {
    {
      std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
      if (!out) throw InputError(path.string(), "cannot open for writing (does the folder exist?)");
      write(out);
      out.flush();
      if (!out) throw InputError(path.string(), "write failed (disk full?)");
    }
    fs::rename(tmp, path);
  } catch (...) {
    std::error_code ignored;
    fs::remove(tmp, ignored);
    throw;
  }
}

void WriteTextFileAtomically(const std::filesystem::path& path, const std::string& text) {
  WriteFileAtomically(path, [&](std::ostream& out) { out << text; });
}

}  // namespace ema::formats
