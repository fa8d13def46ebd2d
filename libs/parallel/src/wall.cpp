#include "relief/parallel/wall.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "relief/base/file_io.h"

namespace relief::parallel {
namespace {
// A wall file describes a grid of displays in a few hundred bytes.
constexpr uint64_t kMaxWallFileBytes = uint64_t{1} << 20;
}  // namespace

lod::PixelRect Wall::display(int index) const {
  const int r = index / columns, c = index % columns;
  lod::PixelRect p{c * (display_width + bezel_x), r * (display_height + bezel_y), display_width,
                   display_height};
  if (static_cast<size_t>(index) < offsets.size()) {
    p.x += offsets[static_cast<size_t>(index)].x;
    p.y += offsets[static_cast<size_t>(index)].y;
  }
  return p;
}

Result<Wall> parse_wall(const std::string& text, const std::string& where) {
  const nlohmann::json j = nlohmann::json::parse(text, nullptr, false);
  if (j.is_discarded() || !j.is_object()) return fail(where + ": not a JSON object");
  auto integer = [&](const nlohmann::json& v, const std::string& name, int lo,
                     int hi) -> Result<int> {
    if (!v.is_number_integer() || v.get<int64_t>() < lo || v.get<int64_t>() > hi) {
      return fail(fmt::format("{}: {} must be an integer in {}..{}", where, name, lo, hi));
    }
    return static_cast<int>(v.get<int64_t>());
  };
  auto pair = [&](const std::string& name, int lo, int hi) -> Result<std::array<int, 2>> {
    const nlohmann::json& v = j.at(name);
    if (!v.is_array() || v.size() != 2)
      return fail(fmt::format("{}: {} must be [x, y]", where, name));
    return std::array<int, 2>{RELIEF_TRY(integer(v[0], name, lo, hi)),
                              RELIEF_TRY(integer(v[1], name, lo, hi))};
  };
  for (const char* name : {"rows", "columns", "display"}) {
    if (!j.contains(name)) return fail(fmt::format("{}: {} is missing", where, name));
  }
  Wall w;
  w.rows = RELIEF_TRY(integer(j["rows"], "rows", 1, 64));
  w.columns = RELIEF_TRY(integer(j["columns"], "columns", 1, 64));
  const auto display = RELIEF_TRY(pair("display", 1, 16384));
  w.display_width = display[0], w.display_height = display[1];
  if (j.contains("bezel")) {
    const auto bezel = RELIEF_TRY(pair("bezel", 0, 4096));
    w.bezel_x = bezel[0], w.bezel_y = bezel[1];
  }
  if (w.virtual_width() > 16384 || w.virtual_height() > 16384) {
    return fail(fmt::format("{}: the wall's virtual view {}x{} is larger than 16384x16384", where,
                            w.virtual_width(), w.virtual_height()));
  }
  if (j.contains("offsets")) {
    const nlohmann::json& o = j["offsets"];
    if (!o.is_array() || o.size() != static_cast<size_t>(w.displays())) {
      return fail(fmt::format("{}: offsets must list [x, y] for each of the {} displays", where,
                              w.displays()));
    }
    for (const nlohmann::json& d : o) {
      if (!d.is_array() || d.size() != 2) return fail(where + ": an offset is not [x, y]");
      w.offsets.push_back({RELIEF_TRY(integer(d[0], "offsets", -4096, 4096)),
                           RELIEF_TRY(integer(d[1], "offsets", -4096, 4096)), 0, 0});
    }
  }
  for (int i = 0; i < w.displays(); ++i) {
    const lod::PixelRect p = w.display(i);
    if (p.x < 0 || p.y < 0 || p.x + p.width > w.virtual_width() ||
        p.y + p.height > w.virtual_height()) {
      return fail(fmt::format("{}: display {} shifted outside the wall's {}x{} view", where, i,
                              w.virtual_width(), w.virtual_height()));
    }
  }
  return w;
}

Result<Wall> read_wall(const std::string& path) {
  const std::string text = RELIEF_TRY(read_text_file(path, kMaxWallFileBytes));
  return parse_wall(text, path);
}

}  // namespace relief::parallel
