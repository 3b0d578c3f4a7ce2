#pragma once
// The words an enum's values are printed and parsed as: one table per enum, read both ways, so a
// name is written once (rather than once in a toString switch and again in a parser).
//   constexpr EnumName<Region> kRegionNames[] = {{Region::Lumbar, "lumbar"}, ...};
//   enumName(kRegionNames, Region::Lumbar) == "lumbar"; parseEnumName(kRegionNames, "lumbar", r)
#include <cstddef>
#include <string_view>

namespace embody {

template <class E>
struct EnumName {
  E value;
  const char* name;
};

// The name of `value`, or `unknown` when the table lacks it.
template <class E, std::size_t N>
constexpr const char* enumName(const EnumName<E> (&table)[N], E value, const char* unknown = "?") {
  for (const EnumName<E>& e : table)
    if (e.value == value) return e.name;
  return unknown;
}

// The value named `text`; false (and `out` untouched) when no entry has that name.
template <class E, std::size_t N>
constexpr bool parseEnumName(const EnumName<E> (&table)[N], std::string_view text, E& out) {
  for (const EnumName<E>& e : table)
    if (text == e.name) {
      out = e.value;
      return true;
    }
  return false;
}

}  // namespace embody
