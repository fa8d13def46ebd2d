#include "memory_store.h"

#include <memory>
#include <utility>

#include <fmt/format.h>

#include "relief/tiles/store_layout.h"

namespace relief::pipeline {
namespace {

// Serves the manifest and level indexes from memory and encodes tiles when
// they are fetched.
class MemorySource final : public tiles::StoreSource {
 public:
  MemorySource(std::string name, TileEncoder encode, std::string manifest,
               std::vector<std::vector<std::byte>> indices)
      : name_(std::move(name)),
        encode_(std::move(encode)),
        manifest_(std::move(manifest)),
        indices_(std::move(indices)) {}

  std::string name() const override { return name_; }
  bool holds_files() const override { return false; }

  Result<std::vector<std::byte>> fetch(const std::string& relative) const override {
    if (relative == tiles::kManifestName) {
      const auto* p = reinterpret_cast<const std::byte*>(manifest_.data());
      return std::vector<std::byte>(p, p + manifest_.size());
    }
    for (size_t level = 0; level < indices_.size(); ++level) {
      if (relative == tiles::level_index_relative_path(static_cast<int>(level))) {
        return indices_[level];
      }
    }
    const auto key = tiles::tile_key_from_relative_path(relative);
    if (!key) return fail(fmt::format("{}/{}: no such file", name_, relative));
    return encode_(*key);
  }

 private:
  std::string name_;
  TileEncoder encode_;
  std::string manifest_;
  std::vector<std::vector<std::byte>> indices_;
};

}  // namespace

Result<tiles::Store> open_memory_store(std::string name, const tiles::Manifest& manifest,
                                       const std::vector<tiles::LevelIndex>& indices,
                                       TileEncoder encode) {
  std::vector<std::vector<std::byte>> serialized(static_cast<size_t>(manifest.max_level) + 1);
  for (const tiles::LevelIndex& index : indices) {
    serialized[static_cast<size_t>(index.level())] = index.serialize();
  }
  auto source = std::make_shared<const MemorySource>(std::move(name), std::move(encode),
                                                     manifest.to_json(), std::move(serialized));
  return tiles::Store::open(std::move(source));
}

}  // namespace relief::pipeline
