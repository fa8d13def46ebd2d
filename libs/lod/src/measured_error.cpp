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

// The drawn mesh's point above (lon, lat) in quad `at`: of the refined mesh
// when there is one.
Result<Vec3> drawn_point(MeshEvaluator& mesh, std::optional<RefinedEvaluator>& refined,
                         const SelectedQuad& at, double lon, double lat) {
  if (!refined) return mesh.mesh_point(at, lon, lat);
  const std::optional<Vec3> p = RELIEF_TRY(refined->point(at, lon, lat));
  if (!p) {
    return fail(fmt::format("refined mesh: no triangle of quad {} holds {},{}", at.key.to_string(),
                            lon, lat));
  }
  return *p;
}

// Pixels between the projections of `data` and `drawn`; none when the data
// point is off screen.
std::optional<double> screen_distance(const View& view, const Vec3& data, const Vec3& drawn) {
  double ax, ay, bx, by;
  if (!view.project(data, ax, ay) || !view.project(drawn, bx, by)) return std::nullopt;
  if (ax < 0 || ay < 0 || ax >= view.width || ay >= view.height) return std::nullopt;
  return std::hypot(ax - bx, ay - by);
}

}  // namespace

Result<std::vector<std::optional<double>>> measure_screen_error_at(
    const View& view, TerrainModel& terrain, const Selection& selection,
    std::span<const DataPoint> points, const RefinedMesh* refined) {
  MeshEvaluator mesh(terrain, selection);
  std::optional<RefinedEvaluator> refined_mesh;
  if (refined) refined_mesh.emplace(terrain, selection, *refined);
  std::vector<std::optional<double>> out;
  out.reserve(points.size());
  for (const DataPoint& p : points) {
    const SelectedQuad* at = mesh.containing(p.lon, p.lat);
    if (!at || !std::isfinite(p.height)) {
      out.emplace_back();
      continue;
    }
    const Vec3 drawn = RELIEF_TRY(drawn_point(mesh, refined_mesh, *at, p.lon, p.lat));
    out.push_back(screen_distance(view, ecef(p.lon, p.lat, p.height), drawn));
  }
  return out;
}

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
    const Vec3 on_mesh = RELIEF_TRY(drawn_point(mesh, refined_mesh, *at, slon, slat));
    const std::optional<double> pixels = screen_distance(view, ecef(slon, slat, height), on_mesh);
    if (!pixels) continue;
    out.max_pixels = std::max(out.max_pixels, *pixels);
    ++out.samples;
  }
  return out;
}

}  // namespace relief::lod
