#include "core_store.h"

#include <algorithm>

#include <fmt/format.h>

#include "relief/base/file_io.h"
#include "relief/tiles/store_layout.h"
#include "relief/tiles/tile_file.h"

namespace relief::ingest {
namespace fs = std::filesystem;

CoreStore::CoreStore(fs::path dir, tiles::TileShape shape, uint64_t memory_budget_bytes)
    : dir_(std::move(dir)), shape_(shape), budget_(memory_budget_bytes) {}

fs::path CoreStore::path_of(const geo::TileKey& key) const {
  return dir_ / tiles::tile_relative_path(key);
}

bool CoreStore::exists(const geo::TileKey& key) const {
  {
    std::lock_guard lock(mutex_);
    auto level = written_.find(key.level);
    if (level != written_.end() && level->second.contains(key)) return true;
  }
  std::error_code ec;
  return fs::exists(path_of(key), ec);
}

CoreStore::Victims CoreStore::insert_locked(const geo::TileKey& key,
                                            std::shared_ptr<const tiles::Raster> core,
                                            bool on_disk) {
  if (auto it = memory_.find(key); it != memory_.end()) {
    used_ -= it->second.core->byte_size();
    lru_.erase(it->second.position);
    memory_.erase(it);
  }
  used_ += core->byte_size();
  lru_.push_front(key);
  memory_.emplace(key, Entry{std::move(core), on_disk, lru_.begin()});
  return evict_locked();
}

CoreStore::Victims CoreStore::evict_locked() {
  Victims victims;
  while (used_ > budget_ && lru_.size() > 1) {
    auto it = memory_.find(lru_.back());
    used_ -= it->second.core->byte_size();
    if (!it->second.on_disk) {
      spilling_.emplace(it->first, it->second.core);
      victims.emplace_back(it->first, std::move(it->second.core));
    }
    lru_.pop_back();
    memory_.erase(it);
  }
  return victims;
}

Status CoreStore::spill(Victims victims) {
  Status status;
  for (auto& [key, core] : victims) {
    // Scratch data favours speed: the lowest zstd level.
    if (status) {
      auto bytes = tiles::encode_tile(*core, 0, {tiles::Codec::Zstd, 0, 0, 1});
      status =
          bytes ? write_file_atomic(path_of(key), *bytes) : Status(std::unexpected(bytes.error()));
    }
    std::lock_guard lock(mutex_);
    spilling_.erase(key);
    if (status) ++spilled_;
  }
  return status;
}

Status CoreStore::write(const geo::TileKey& key, tiles::Raster core) {
  Victims victims;
  {
    std::lock_guard lock(mutex_);
    written_[key.level].insert(key);
    victims = insert_locked(key, std::make_shared<const tiles::Raster>(std::move(core)), false);
  }
  return spill(std::move(victims));
}

Result<std::shared_ptr<const tiles::Raster>> CoreStore::read(const geo::TileKey& key) {
  {
    std::lock_guard lock(mutex_);
    if (auto it = memory_.find(key); it != memory_.end()) {
      lru_.splice(lru_.begin(), lru_, it->second.position);
      return it->second.core;
    }
    if (auto it = spilling_.find(key); it != spilling_.end()) return it->second;
  }
  const fs::path path = path_of(key);
  std::error_code ec;
  if (!fs::exists(path, ec)) return std::shared_ptr<const tiles::Raster>();
  auto bytes = read_file(path, tiles::max_tile_file_bytes(shape_));
  if (!bytes) return std::unexpected(bytes.error());
  auto tile = tiles::decode_tile(*bytes, path.string(), shape_);
  if (!tile) return std::unexpected(tile.error());
  auto raster = std::make_shared<const tiles::Raster>(std::move(tile->raster));
  Victims victims;
  {
    std::lock_guard lock(mutex_);
    victims = insert_locked(key, raster, true);
  }
  RELIEF_CHECK(spill(std::move(victims)));
  return raster;
}

std::vector<geo::TileKey> CoreStore::list(int level) const {
  std::set<geo::TileKey> keys;
  {
    std::lock_guard lock(mutex_);
    if (auto it = written_.find(level); it != written_.end()) keys = it->second;
  }
  const fs::path root = dir_ / fmt::format("{}", level);
  std::error_code ec;
  if (fs::is_directory(root, ec)) {
    for (auto it = fs::recursive_directory_iterator(root, ec);
         it != fs::recursive_directory_iterator(); it.increment(ec)) {
      if (ec || !it->is_regular_file() || is_temporary_file(it->path())) continue;
      const std::string rel = fs::relative(it->path(), dir_).generic_string();
      if (auto key = tiles::tile_key_from_relative_path(rel)) keys.insert(*key);
    }
  }
  std::vector<geo::TileKey> sorted(keys.begin(), keys.end());
  std::sort(sorted.begin(), sorted.end(),
            [](const auto& a, const auto& b) { return std::tie(a.y, a.x) < std::tie(b.y, b.x); });
  return sorted;
}

bool CoreStore::all_on_disk(int level) const {
  std::lock_guard lock(mutex_);
  for (const auto& [key, entry] : memory_) {
    if (key.level == level && !entry.on_disk) return false;
  }
  for (const auto& [key, core] : spilling_) {
    if (key.level == level) return false;
  }
  return true;
}

Status CoreStore::shrink_budget(uint64_t bytes) {
  const uint64_t floor = 16 * shape_.raster_bytes();
  Victims victims;
  {
    std::lock_guard lock(mutex_);
    budget_ = budget_ > floor + bytes ? budget_ - bytes : std::min(budget_, floor);
    victims = evict_locked();
  }
  return spill(std::move(victims));
}

uint64_t CoreStore::budget() const {
  std::lock_guard lock(mutex_);
  return budget_;
}

uint64_t CoreStore::spilled() const {
  std::lock_guard lock(mutex_);
  return spilled_;
}

}  // namespace relief::ingest
