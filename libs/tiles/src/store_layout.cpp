#include "relief/tiles/store_layout.h"

#include <charconv>
#include <vector>

#include <fmt/format.h>

namespace relief::tiles {
namespace {
int block_count(int level) {
  return level == 0 ? 1 : (2 * level + 11) / 12;
}
}  // namespace

std::string tile_relative_path(const geo::TileKey& key) {
  const uint64_t m = key.morton();
  std::string path = fmt::format("{}", key.level);
  for (int b = block_count(key.level) - 1; b >= 0; --b) {
    path += fmt::format("/{:03x}", (m >> (12 * b)) & 0xFFF);
  }
  return path + kTileExtension;
}

std::string level_index_relative_path(int level) {
  return fmt::format("{}/{}", level, kLevelIndexName);
}

std::optional<geo::TileKey> tile_key_from_relative_path(const std::string& path) {
  const std::string ext = kTileExtension;
  if (path.size() <= ext.size() || path.compare(path.size() - ext.size(), ext.size(), ext) != 0) {
    return std::nullopt;
  }
  std::vector<std::string> parts;
  size_t start = 0;
  const std::string body = path.substr(0, path.size() - ext.size());
  for (size_t slash; (slash = body.find('/', start)) != std::string::npos; start = slash + 1) {
    parts.push_back(body.substr(start, slash - start));
  }
  parts.push_back(body.substr(start));
  int level = -1;
  auto [p, ec] = std::from_chars(parts[0].data(), parts[0].data() + parts[0].size(), level);
  if (ec != std::errc() || p != parts[0].data() + parts[0].size() || level < 0 ||
      level > geo::kMaxLevel || static_cast<int>(parts.size()) != 1 + block_count(level)) {
    return std::nullopt;
  }
  uint64_t m = 0;
  for (size_t i = 1; i < parts.size(); ++i) {
    unsigned block = 0;
    auto [q, ec2] = std::from_chars(parts[i].data(), parts[i].data() + parts[i].size(), block, 16);
    if (ec2 != std::errc() || q != parts[i].data() + parts[i].size() || parts[i].size() != 3) {
      return std::nullopt;
    }
    m = (m << 12) | block;
  }
  if (level < 32 && (m >> (2 * level)) != 0) return std::nullopt;
  return geo::TileKey::from_morton(level, m);
}

}  // namespace relief::tiles
