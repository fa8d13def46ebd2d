#include "relief/tiles/store_source.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdlib>

#include <fmt/format.h>

#include "relief/base/file_io.h"
#include "relief/base/units.h"
#include "relief/tiles/level_index.h"
#include "relief/tiles/manifest.h"
#include "relief/tiles/store.h"
#include "relief/tiles/store_layout.h"
#include "relief/tiles/tile_file.h"

namespace relief::tiles {
namespace {

class LocalSource final : public StoreSource {
 public:
  explicit LocalSource(std::filesystem::path root) : root_(std::move(root)) {}
  std::string name() const override { return root_.string(); }
  Result<std::vector<std::byte>> fetch(const std::string& relative) const override {
    auto bytes = RELIEF_TRY(read_file(root_ / relative, caps_.cap(relative)));
    caps_.learn(relative, bytes);
    return bytes;
  }

 private:
  std::filesystem::path root_;
  mutable FileCaps caps_;
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
  // Any other file is not one of a store's: the manifest's cap bounds it.
  if (!relative.ends_with(kLevelIndexName)) return kMaxManifestBytes;
  // "L/index.rli": header, presence bitmap and a record per tile.
  const int level = std::atoi(relative.c_str());
  if (level < 0 || level > 13) return kMaxLevelIndexBytes;
  const uint64_t tiles = uint64_t{1} << (2 * level);
  return std::min(kMaxLevelIndexBytes, 64 + tiles / 8 + kLevelIndexRecordSize * tiles);
}

uint64_t FileCaps::cap(const std::string& relative) const {
  std::lock_guard lock(mutex_);
  return max_file_bytes(relative, shape_);
}

void FileCaps::learn(const std::string& relative, std::span<const std::byte> bytes) {
  if (relative != kManifestName) return;
  const std::string text(reinterpret_cast<const char*>(bytes.data()), bytes.size());
  auto manifest = Manifest::from_json(text, relative);
  if (!manifest) return;
  auto shape = tile_shape_of(*manifest);
  if (!shape) return;
  std::lock_guard lock(mutex_);
  shape_ = *shape;
}

Status StoreSource::verify(const std::string& relative, std::span<const std::byte> bytes) {
  if (relative == kManifestName) {
    const std::string text(reinterpret_cast<const char*>(bytes.data()), bytes.size());
    auto manifest = Manifest::from_json(text, relative);
    // A store of format 1 is whole: Store::open refuses it with the way out,
    // rather than a source retrying it as if it were corrupt.
    if (!manifest && manifest_format_version(text) != 1) return std::unexpected(manifest.error());
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
  RELIEF_CHECK(LevelIndex::parse_for_upgrade(bytes, relative));  // whole, of either version
  return {};
}

}  // namespace relief::tiles
