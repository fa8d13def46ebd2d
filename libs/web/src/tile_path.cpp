#include "relief/web/tile_path.h"

#include "relief/geo/tile_key.h"

namespace relief::web {
namespace {

std::optional<uint32_t> decimal(std::string_view s) {
  if (s.empty() || s.size() > 10 || (s.size() > 1 && s[0] == '0')) return std::nullopt;
  uint64_t v = 0;
  for (const char c : s) {
    if (c < '0' || c > '9') return std::nullopt;
    v = v * 10 + static_cast<uint64_t>(c - '0');
  }
  if (v >= (uint64_t{1} << 31)) return std::nullopt;
  return static_cast<uint32_t>(v);
}

}  // namespace

std::optional<TilePath> parse_tile_path(std::string_view path, std::string_view extension) {
  if (!path.ends_with(extension)) return std::nullopt;
  path.remove_suffix(extension.size());
  uint32_t parts[3];
  for (int i = 0; i < 3; ++i) {
    const size_t slash = path.find('/');
    if ((i < 2) != (slash != std::string_view::npos)) return std::nullopt;
    auto v = decimal(path.substr(0, slash));
    if (!v) return std::nullopt;
    parts[i] = *v;
    path = i < 2 ? path.substr(slash + 1) : std::string_view{};
  }
  if (parts[0] > static_cast<uint32_t>(geo::kMaxLevel)) return std::nullopt;
  return TilePath{static_cast<int>(parts[0]), parts[1], parts[2]};
}

std::string_view target_path(std::string_view target) {
  return target.substr(0, target.find_first_of("?#"));
}

}  // namespace relief::web
