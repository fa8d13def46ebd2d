#pragma once
// Strict parsing of web tile paths ("{z}/{x}/{y}.ext"): decimal digits only,
// no sign, no leading zero, no empty or extra segment, z <= 30 and x, y
// below 2^31. Anything else is not a tile (the server answers 404), so no
// request maps to a surprising tile or reaches a file.
#include <cstdint>
#include <optional>
#include <string_view>

namespace relief::web {

struct TilePath {
  int z = 0;
  uint32_t x = 0, y = 0;
};

// `path` without its route prefix, e.g. "10/2048/745.terrain" with
// extension ".terrain".
std::optional<TilePath> parse_tile_path(std::string_view path, std::string_view extension);

// The request target's path: the query ("?v=1.0.0&extensions=...", which
// CesiumJS appends) and fragment cut off.
std::string_view target_path(std::string_view target);

}  // namespace relief::web
