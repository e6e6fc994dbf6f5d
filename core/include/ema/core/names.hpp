// One name table per enum (string <-> enum): the CLI parses choices with it instead of
// if-chains, and messages list the choices from the same table.
#pragma once

#include <cstddef>
#include <string>

namespace ema {

template <class Enum>
struct EnumName {
  Enum value;
  const char* name;
};

/// The value named `text` (exact match); false when the table has no such name.
template <class Enum, std::size_t N>
bool FromName(const EnumName<Enum> (&table)[N], const std::string& text, Enum* value) {
  for (const EnumName<Enum>& entry : table)
    if (text == entry.name) {
      *value = entry.value;
      return true;
    }
  return false;
}

/// The name of `value` ("" when the table lacks it).
template <class Enum, std::size_t N>
const char* NameOf(const EnumName<Enum> (&table)[N], Enum value) {
  for (const EnumName<Enum>& entry : table)
    if (entry.value == value) return entry.name;
  return "";
}

/// The names for a message: "a, b or c".
template <class Enum, std::size_t N>
std::string NameList(const EnumName<Enum> (&table)[N]) {
  std::string out;
  for (std::size_t i = 0; i < N; ++i) out += (i == 0 ? "" : i + 1 == N ? " or " : ", ") + std::string(table[i].name);
  return out;
}

}  // namespace ema
