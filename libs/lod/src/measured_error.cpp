#include "relief/lod/measured_error.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <random>
#include <unordered_map>

#include <fmt/format.h>

#include "relief/lod/mesh_evaluator.h"
#include "relief/lod/refined_evaluator.h"
#include "relief/tiles/full_mesh.h"

namespace relief::lod {

namespace {

// Which finest samples the guarantee covers (docs/store-format.md): not
// nodata, and, above the store's finest level, not where the drawn level's
// full mesh reaches a nodata sample (the fall-off at the data's edge or a
// void, which the level's geometric error leaves out). Tiles with every sample
// valid answer from the index; the others are decoded with their nodata when
// `decode` allows reading them, else their samples are left out.
class Coverage {
 public:
  Coverage(const tiles::Store& store, bool decode) : store_(store), decode_(decode) {}

  Result<bool> covered(const geo::TileKey& finest, int i, int j, const SelectedQuad& drawn,
                       double lon, double lat) {
    const int w = store_.grid().width(), h = store_.grid().height(), b = store_.grid().border();
    if (!full(finest)) {
      if (!decode_) return false;
      const tiles::Raster& t = *RELIEF_TRY(raw(finest));
      if (std::isnan(t.f32()[static_cast<size_t>(j + b) * t.width() + i + b])) return false;
    }
    const int level = std::min(drawn.key.level, store_.manifest().max_level);
    if (level >= store_.manifest().max_level) return true;
    const geo::TileKey k{level, drawn.key.x >> (drawn.key.level - level),
                         drawn.key.y >> (drawn.key.level - level)};
    const geo::GeoBox kb = k.bounds();
    const double x = (lon - kb.west) / kb.width() * w, y = (kb.north - lat) / kb.height() * h;
    if (full(k) && x >= 1.5 && y >= 1.5 && x <= w - 1.5 && y <= h - 1.5) return true;
    // No tile of its own: a level above the store's coarsest, which draws no
    // data (only interactive frames waiting for the tiles below draw one),
    // or a hole of a store of sparse depth (left out: conservative).
    if (!decode_ || !store_.has_tile(k)) return false;
    return tiles::full_mesh_stencil_valid(*RELIEF_TRY(raw(k)), b, x, y);
  }

 private:
  bool full(const geo::TileKey& k) const {
    const tiles::IndexEntry* e = store_.index(k.level).find(k);
    return e && e->valid_count == static_cast<uint32_t>(store_.grid().width()) *
                                      static_cast<uint32_t>(store_.grid().height());
  }
  Result<const tiles::Raster*> raw(const geo::TileKey& k) {
    auto it = raw_.find(k);
    if (it == raw_.end()) {
      tiles::Tile t = RELIEF_TRY(store_.read_tile(k));
      it = raw_.emplace(k, std::move(t.raster)).first;
    }
    return &it->second;
  }

  const tiles::Store& store_;
  const bool decode_;
  std::unordered_map<geo::TileKey, tiles::Raster, geo::TileKeyHash> raw_;
};

}  // namespace

Result<MeasuredError> measure_screen_error(const View& view, TerrainModel& terrain,
                                           const Selection& selection, const geo::GeoBox& extent,
                                           int samples, const RefinedMesh* refined,
                                           bool read_tiles) {
  MeshEvaluator mesh(terrain, selection);
  std::optional<RefinedEvaluator> refined_mesh;
  if (refined) refined_mesh.emplace(terrain, selection, *refined);
  std::mt19937 rng(5);
  const int finest = terrain.data_max_level();
  const double n = std::ldexp(1.0, finest);
  const int w = terrain.tile_width(), h = terrain.tile_height(), b = terrain.border();
  std::uniform_real_distribution<double> unit(0, 1);
  MeasuredError out;
  if (!terrain.store()) return out;
  Coverage coverage(*terrain.store(), read_tiles);
  for (int s = 0; s < samples && !selection.quads.empty(); ++s) {
    const SelectedQuad& q = selection.quads[rng() % selection.quads.size()];
    const geo::GeoBox all = q.key.bounds();
    const geo::GeoBox qb{std::max(all.west, extent.west), std::max(all.south, extent.south),
                         std::min(all.east, extent.east), std::min(all.north, extent.north)};
    if (qb.west >= qb.east || qb.south >= qb.north) continue;  // no data: height 0 in both
    const double lon = qb.west + unit(rng) * qb.width(), lat = qb.north - unit(rng) * qb.height();
    const geo::TileKey k{finest, static_cast<uint32_t>((lon + 180) / 360 * n),
                         static_cast<uint32_t>((90 - lat) / 180 * n)};
    const geo::GeoBox kb = k.bounds();
    const int i = std::clamp(static_cast<int>((lon - kb.west) / kb.width() * w), 0, w - 1);
    const int j = std::clamp(static_cast<int>((kb.north - lat) / kb.height() * h), 0, h - 1);
    const double slon = kb.west + (i + 0.5) * kb.width() / w;
    const double slat = kb.north - (j + 0.5) * kb.height() / h;
    const SelectedQuad* at = mesh.containing(slon, slat);
    if (!at) continue;
    if (!terrain.available(k)) continue;  // interactive frames: not resident, not drawn
    auto tile = RELIEF_TRY(terrain.tile(k));
    if (!tile) continue;  // no data: drawn at height 0 by both
    if (!RELIEF_TRY(coverage.covered(k, i, j, *at, slon, slat))) continue;
    const double height =
        tile->f32()[static_cast<size_t>(j + b) * static_cast<size_t>(tile->width()) +
                    static_cast<size_t>(i + b)];
    Vec3 on_mesh;
    if (refined_mesh) {
      const std::optional<Vec3> p = RELIEF_TRY(refined_mesh->point(*at, slon, slat));
      if (!p)
        return fail(fmt::format("refined mesh: no triangle of quad {} holds {},{}",
                                at->key.to_string(), slon, slat));
      on_mesh = *p;
    } else {
      on_mesh = RELIEF_TRY(mesh.mesh_point(*at, slon, slat));
    }
    double ax, ay, bx, by;
    if (!view.project(ecef(slon, slat, height), ax, ay) || !view.project(on_mesh, bx, by)) continue;
    if (ax < 0 || ay < 0 || ax >= view.width || ay >= view.height) continue;
    out.max_pixels = std::max(out.max_pixels, std::hypot(ax - bx, ay - by));
    ++out.samples;
  }
  return out;
}

}  // namespace relief::lod
