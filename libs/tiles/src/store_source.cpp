#include "relief/tiles/store_source.h"

#include <algorithm>
#include <cstdlib>

#include <fmt/format.h>

#include "relief/base/file_io.h"
#include "relief/tiles/level_index.h"
#include "relief/tiles/manifest.h"
#include "relief/tiles/store_layout.h"
#include "relief/tiles/tile_file.h"

namespace relief::tiles {
namespace {

class LocalSource final : public StoreSource {
 public:
  explicit LocalSource(std::filesystem::path root) : root_(std::move(root)) {}
  std::string name() const override { return root_.string(); }
  Result<std::vector<std::byte>> fetch(const std::string& relative) const override {
    return read_file(root_ / relative);
  }

 private:
  std::filesystem::path root_;
};

}  // namespace

std::shared_ptr<const StoreSource> local_source(const std::filesystem::path& root) {
  return std::make_shared<LocalSource>(root);
}

uint64_t max_file_bytes(const std::string& relative, const std::optional<TileShape>& shape) {
  if (relative == kManifestName) return kMaxManifestBytes;
  if (relative.ends_with(kTileExtension)) {
    if (shape) return max_tile_file_bytes(*shape);
    // 2^13 x 2^12 samples with a border of 2^12, the largest grid TileGrid allows.
    return max_tile_file_bytes({SampleType::Float32, 1, 16384, 12288, 4096});
  }
  // "L/index.rli": header, presence bitmap and a 16-byte record per tile.
  const int level = std::atoi(relative.c_str());
  if (level < 0 || level > 13) return kMaxLevelIndexBytes;
  const uint64_t tiles = uint64_t{1} << (2 * level);
  return std::min(kMaxLevelIndexBytes, 64 + tiles / 8 + 16 * tiles);
}

Status StoreSource::verify(const std::string& relative, std::span<const std::byte> bytes) {
  if (relative == kManifestName) {
    const std::string text(reinterpret_cast<const char*>(bytes.data()), bytes.size());
    RELIEF_CHECK(Manifest::from_json(text, relative));
    return {};
  }
  if (relative.ends_with(kTileExtension)) {
    const TileHeader h = RELIEF_TRY(parse_tile_header(bytes, relative));
    const auto payload = bytes.subspan(kTileHeaderSize);
    if (payload.size() != h.payload_size || crc32_of(payload) != h.payload_crc) {
      return fail(fmt::format("{}: payload checksum mismatch", relative));
    }
    return {};
  }
  RELIEF_CHECK(LevelIndex::parse(bytes, relative));
  return {};
}

}  // namespace relief::tiles
