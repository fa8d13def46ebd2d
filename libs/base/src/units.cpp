#include "relief/base/units.h"

#include <fmt/format.h>
#include <charconv>
#include <cmath>

namespace relief {

Result<uint64_t> parse_byte_size(std::string_view text) {
  double value = 0;
  auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (ec != std::errc() || value < 0) return fail(fmt::format("'{}' is not a size", text));
  std::string_view unit(ptr, text.data() + text.size() - ptr);
  double scale = 1;
  if (unit.empty() || unit == "B")
    scale = 1;
  else if (unit == "K" || unit == "KiB" || unit == "k")
    scale = 1024.0;
  else if (unit == "M" || unit == "MiB")
    scale = 1024.0 * 1024;
  else if (unit == "G" || unit == "GiB")
    scale = 1024.0 * 1024 * 1024;
  else if (unit == "T" || unit == "TiB")
    scale = 1024.0 * 1024 * 1024 * 1024;
  else
    return fail(
        fmt::format("'{}' has an unknown unit '{}' (use B, KiB, MiB, GiB, TiB)", text, unit));
  const double bytes = std::round(value * scale);
  // 2^64 bytes: far beyond any machine, and beyond what uint64_t holds.
  if (!(bytes < 18446744073709551616.0)) return fail(fmt::format("'{}' is too large", text));
  return static_cast<uint64_t>(bytes);
}

std::string format_bytes(uint64_t bytes) {
  const char* units[] = {"B", "KiB", "MiB", "GiB", "TiB"};
  double v = static_cast<double>(bytes);
  int u = 0;
  while (v >= 1024 && u < 4) {
    v /= 1024;
    ++u;
  }
  return u == 0 ? fmt::format("{} B", bytes) : fmt::format("{:.1f} {}", v, units[u]);
}

}  // namespace relief
