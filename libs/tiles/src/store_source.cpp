#include "relief/tiles/store_source.h"

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
