// Elevation and imagery tiles into the texture arrays (TileSlots): uploaded
// when they arrive, an ancestor's imagery meanwhile.
#include <algorithm>
#include <chrono>
#include <cmath>

#include "gl_terrain_renderer.h"

namespace relief::render {
namespace {

using geo::TileKey;
using Clock = std::chrono::steady_clock;

}  // namespace

void GlTerrainRenderer::set_on_growth_ahead(std::function<void(uint64_t)> on_growth_ahead) {
  slots_.set_on_growth_ahead(std::move(on_growth_ahead));
}

bool GlTerrainRenderer::has_elevation_texture(const TileKey& tile) const {
  return slots_.contains({tile, false});
}

Result<FrameStats> GlTerrainRenderer::preload_elevation(std::span<const TileKey> tiles) {
  const auto start = Clock::now();
  FrameStats stats;
  gl::Uploads uploads;
  const uint64_t before = slots_.uploads();
  for (const TileKey& tile : tiles) {
    if (!slots_.contains({tile, false})) RELIEF_TRY(height_layer(tile, uploads));
  }
  stats.uploads = static_cast<uint32_t>(slots_.uploads() - before);
  stats.texture_bytes = uploads.textures;
  stats.prepare_seconds = std::chrono::duration<double>(Clock::now() - start).count();
  return stats;
}

// The texture layer of an elevation tile, uploaded when it arrives;
// nullopt where there is no data.
Result<std::optional<int>> GlTerrainRenderer::height_layer(const std::optional<TileKey>& key,
                                                           gl::Uploads& uploads) {
  if (!key) return std::optional<int>();
  if (auto layer = slots_.find({*key, false})) return layer;
  const lod::TerrainModel::TilePtr tile = RELIEF_TRY(elevation_.tile(*key));
  if (!tile) return std::optional<int>();
  return std::optional<int>(RELIEF_TRY(
      slots_.insert({*key, false}, tile->width(), tile->height(), tile->f32().data(), uploads)));
}

// The imagery of a quad: the layer of the imagery tile at the quad's level
// (or the imagery's finest), else of its nearest ancestor whose texture or
// decoded tile is at hand (non-blocking providers: the wanted tile is
// requested meanwhile). Colour has no cracks to fear, so any ancestor will do.
Result<std::pair<lod::DataWindow, std::optional<int>>> GlTerrainRenderer::imagery_for(
    const lod::SelectedQuad& quad, gl::Uploads& uploads) {
  lod::DataWindow w;
  std::optional<int> layer;
  if (!imagery_) return std::pair{w, layer};
  const TileKey& key = quad.key;
  const int finest = std::min(key.level, imagery_->manifest().max_level);
  int m = key.level - finest;
  for (TileKey a{finest, key.x >> m, key.y >> m};; a = *a.parent(), ++m) {
    if (imagery_->has_tile(a)) {
      if (auto l = slots_.find({a, true})) {
        layer = l;
      } else if (const lod::TilePtr tile = RELIEF_TRY(imagery_tiles_->get(a))) {
        // premultiplied by decode_tile
        layer = RELIEF_TRY(
            slots_.insert({a, true}, tile->width(), tile->height(), tile->u8().data(), uploads));
      } else if (a.level == finest) {
        imagery_tiles_->request(a, quad.priority);
      }
      if (layer) {
        w.tile = a;
        w.width = std::ldexp(imagery_->grid().width(), -m);
        w.height = std::ldexp(imagery_->grid().height(), -m);
        w.x0 = (key.x - (a.x << m)) * w.width;
        w.y0 = (key.y - (a.y << m)) * w.height;
        break;
      }
    }
    if (a.level == 0) break;
  }
  return std::pair{w, layer};
}

}  // namespace relief::render
