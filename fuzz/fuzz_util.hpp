// Shared helpers of the libFuzzer targets (docs/reliability.md). The readers are file based, so
// each input is written to files in a per-process scratch folder (on /dev/shm when there is
// one: no disk traffic). Multi-file inputs (a model with its curve and matrices, a project with
// its model and data) are one byte string cut at the separator line kSeparator into parts.
#pragma once

#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>
#include <vector>

namespace ema::fuzz {

inline constexpr std::string_view kSeparator = "\n--8<--\n";

inline const std::filesystem::path& ScratchDir() {
  static const std::filesystem::path dir = [] {
    std::error_code ec;
    const std::filesystem::path base =
        std::filesystem::is_directory("/dev/shm", ec) ? std::filesystem::path("/dev/shm") : std::filesystem::temp_directory_path();
    std::filesystem::path d = base / ("ema_fuzz_" + std::to_string(getpid()));
    std::filesystem::create_directories(d);
    return d;
  }();
  return dir;
}

inline std::filesystem::path WriteScratch(const std::string& name, std::string_view bytes) {
  const std::filesystem::path p = ScratchDir() / name;
  std::ofstream out(p, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  return p;
}

/// The input cut at kSeparator; at most `max_parts` parts (the last keeps any further separators).
inline std::vector<std::string_view> SplitParts(const std::uint8_t* data, std::size_t size, std::size_t max_parts) {
  std::string_view rest(reinterpret_cast<const char*>(data), size);
  std::vector<std::string_view> parts;
  while (parts.size() + 1 < max_parts) {
    const std::size_t p = rest.find(kSeparator);
    if (p == std::string_view::npos) break;
    parts.push_back(rest.substr(0, p));
    rest.remove_prefix(p + kSeparator.size());
  }
  parts.push_back(rest);
  return parts;
}

/// Writes the parts under `names` (missing parts: the file is removed, so a stale one never
/// leaks from the previous input).
inline void WriteParts(const std::vector<std::string_view>& parts, const std::vector<std::string>& names) {
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (i < parts.size()) {
      WriteScratch(names[i], parts[i]);
    } else {
      std::error_code ec;
      std::filesystem::remove(ScratchDir() / names[i], ec);
    }
  }
}

}  // namespace ema::fuzz
