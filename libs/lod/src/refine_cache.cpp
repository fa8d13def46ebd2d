#include "refine_cache.h"

#include <bit>

namespace relief::lod {

MarkGrid grid_of(const TerrainModel& terrain) {
  return MarkGrid(std::countr_zero(static_cast<uint32_t>(terrain.tile_width())));
}

namespace {

bool same_window(const DataWindow& a, const DataWindow& b) {
  return a.tile == b.tile && a.x0 == b.x0 && a.y0 == b.y0 && a.width == b.width &&
         a.height == b.height;
}

}  // namespace

bool EdgeInputs::operator==(const EdgeInputs& o) const {
  return own_tile == o.own_tile && parent_tile == o.parent_tile && same_window(own, o.own) &&
         same_window(parent, o.parent) && coarse_sides == o.coarse_sides &&
         coarse_corners == o.coarse_corners;
}

std::shared_ptr<const SideEdges> RefineCache::Impl::find_edges(const geo::TileKey& key,
                                                               const EdgeInputs& in) {
  std::lock_guard lock(mutex);
  for (auto* map : {&edges, &last_edges}) {
    if (auto it = map->find(key); it != map->end() && it->second.inputs == in) {
      edges[key] = it->second;
      return it->second.edges;
    }
  }
  return nullptr;
}

void RefineCache::Impl::keep_edges(const geo::TileKey& key, const EdgeInputs& in,
                                   std::shared_ptr<const SideEdges> e) {
  std::lock_guard lock(mutex);
  edges[key] = {in, std::move(e)};
}

void RefineCache::Impl::end_frame(const TerrainModel& terrain) {
  std::vector<geo::TileKey> evicted;
  {
    std::lock_guard lock(mutex);
    last_edges.swap(edges);
    edges.clear();
    terrain.for_each_held([&](const geo::TileKey& key) {
      if (auto it = entries.find(key); it != entries.end()) it->second.used = frame;
    });
    ++frame;
    evict_over_budget(evicted);
  }
  for (const geo::TileKey& k : evicted) terrain.provider().forget(k);
}

void RefineCache::Impl::evict_over_budget(std::vector<geo::TileKey>& evicted) {
  for (auto it = lru.end(); bytes > budget && it != lru.begin();) {
    --it;
    auto old = entries.find(*it);
    if (old->second.used + 1 >= frame || it->level == 0) continue;
    bytes -= old->second.errors->bytes();
    evicted.push_back(*it);
    entries.erase(old);
    it = lru.erase(it);
  }
}

bool RefineCache::Impl::contains(const geo::TileKey& key) {
  std::lock_guard lock(mutex);
  return entries.contains(key);
}

void RefineCache::Impl::put(const geo::TileKey& key, std::shared_ptr<const DiamondErrors> errors,
                            bool prepared) {
  std::lock_guard lock(mutex);
  if (auto it = entries.find(key); it != entries.end()) {  // measured twice: the same errors
    lru.splice(lru.begin(), lru, it->second.at);
    it->second.used = frame;
    return;
  }
  bytes += errors->bytes();
  lru.push_front(key);
  entries[key] = {std::move(errors), lru.begin(), prepared, frame};
}

Result<std::shared_ptr<const DiamondErrors>> RefineCache::Impl::get(TerrainModel& terrain,
                                                                    const MarkGrid& grid,
                                                                    const geo::TileKey& key,
                                                                    RefineStats& stats) {
  {
    std::lock_guard lock(mutex);
    if (auto it = entries.find(key); it != entries.end()) {
      lru.splice(lru.begin(), lru, it->second.at);
      stats.tiles_prepared += it->second.prepared;
      it->second.prepared = false;
      it->second.used = frame;
      return it->second.errors;
    }
  }
  const TerrainModel::TilePtr tile = RELIEF_TRY(terrain.tile(key));
  if (!tile) return std::shared_ptr<const DiamondErrors>{};
  auto errors =
      std::make_shared<const DiamondErrors>(measure_diamonds(grid, *tile, terrain.border()));
  ++stats.tiles_measured;
  put(key, errors, false);
  return errors;
}

RefineCache::RefineCache(uint64_t budget_bytes) : impl_(std::make_shared<Impl>()) {
  impl_->budget = budget_bytes;
}
RefineCache::~RefineCache() = default;
uint64_t RefineCache::bytes() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->bytes;
}
size_t RefineCache::tiles() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->entries.size();
}

void RefineCache::prepare_on_load(TerrainModel& terrain) {
  if (terrain.blocking() || !terrain.store()) return;
  const MarkGrid grid = grid_of(terrain);
  const int border = terrain.border(), data_max = terrain.data_max_level();
  // The hook runs on the loader's threads and may outlive this cache: it
  // holds a weak pointer and does nothing once the cache is gone.
  terrain.add_prepare([cache = std::weak_ptr<Impl>(impl_), grid, border, data_max](
                          const geo::TileKey& key, const tiles::Raster& tile) {
    if (key.level > data_max) return;
    const std::shared_ptr<Impl> impl = cache.lock();
    if (!impl || impl->contains(key)) return;
    impl->put(key, std::make_shared<const DiamondErrors>(measure_diamonds(grid, tile, border)),
              true);
  });
  // Tiles resident before the hook (the loader reads level 0 at creation).
  for (const tiles::IndexEntry& e : terrain.store()->index(0).entries()) {
    if (impl_->contains(e.key) || !terrain.available(e.key)) continue;
    auto tile = terrain.tile(e.key);
    if (!tile || !*tile) continue;  // refine() will say what is wrong
    impl_->put(e.key, std::make_shared<const DiamondErrors>(measure_diamonds(grid, **tile, border)),
               true);
  }
}

}  // namespace relief::lod
