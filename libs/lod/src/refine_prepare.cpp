// Refinement before any decision: the frame's checks, each quad's terms of
// the split criterion (its grid's geometry, its data's diamond errors, its
// side heights), the last frames' decisions matched and the splits no
// criterion decides.
#include <algorithm>
#include <cassert>
#include <cmath>

#include <fmt/format.h>

#include "refiner.h"
#include "relief/geo/ellipsoid.h"

namespace relief::lod::refinement {

const SinCos* StepTables::of(int level, int32_t n) {
  if (n != n_) {
    by_level_.clear();
    n_ = n;
  }
  if (by_level_.size() <= static_cast<size_t>(level)) by_level_.resize(level + 1);
  std::vector<SinCos>& steps = by_level_[static_cast<size_t>(level)];
  if (steps.empty()) {
    const double cell = geo::TileKey{level, 0, 0}.bounds().height() / n;
    steps.reserve(static_cast<size_t>(2 * n + 1));
    for (int32_t i = 0; i <= 2 * n; ++i) steps.emplace_back(i * cell * kDegree);
  }
  return steps.data();
}

// The frame's checks and the terms of every quad, the history matched and
// the splits that decisions do not make (sides shared with finer quads,
// reused decisions).
Status Refiner::prepare() {
  int deepest = 0;
  bool linked = selection_.quads.size() <= 1;
  for (const SelectedQuad& q : selection_.quads) {
    if (q.key.level > terrain_.data_max_level()) {
      return fail(fmt::format(
          "refine: quad {} is deeper than the store's finest level {}; cap the selection there",
          q.key.to_string(), terrain_.data_max_level()));
    }
    deepest = std::max(deepest, q.key.level);
    for (int32_t n : q.neighbours) linked |= n >= 0;
  }
  if (!linked) {
    return fail(
        "refine: the selection has no neighbour indices (SelectionOptions::neighbour_indices)");
  }
  deepest_ = deepest;
  globe_width_ = int64_t{2} * grid_.n() << deepest;
  assert(quads_.size() == selection_.quads.size());
  marks_.reset(grid_, quads_.size());
  for (size_t i = 0; i < quads_.size(); ++i)
    RELIEF_CHECK(prepare(static_cast<int>(i), selection_.quads[i], quads_[i]));
  if (history_) match_history();
  if (reuse_all_) return {};
  // A side shared with finer quads is split at its midpoint (their corner).
  for (size_t i = 0; i < quads_.size(); ++i) {
    const uint8_t finer = selection_.quads[i].finer_sides;
    const int32_t n = grid_.n();
    const int q = static_cast<int>(i);
    if (finer & kWest) split(q, {0, n / 2});
    if (finer & kEast) split(q, {2 * n, n / 2});
    for (int32_t x : {n / 2, 3 * n / 2}) {
      if (finer & kNorth) split(q, {x, 0});
      if (finer & kSouth) split(q, {x, n});
    }
  }
  if (history_) apply_history();
  return {};
}

// One quad's terms of the criterion, and its halves' centres split.
Status Refiner::prepare(int index, const SelectedQuad& s, Quad& q) {
  const int32_t n = grid_.n();
  q.selected = &s;
  q.scale = int64_t{1} << (deepest_ - s.key.level);
  q.ox = int64_t{s.key.x} * 2 * n * q.scale;
  q.oy = int64_t{s.key.y} * n * q.scale;
  q.bounds = s.key.bounds();
  q.cell = q.bounds.height() / n;
  q.west = SinCos(q.bounds.west * kDegree);
  q.north = SinCos(q.bounds.north * kDegree);
  q.steps = steps_.of(s.key.level, n);
  q.normals.resize(static_cast<size_t>(n) + 1);
  for (int32_t y = 0; y <= n; ++y) {
    const SinCos& step = q.steps[y];
    const double sin_lat = q.north.s * step.c - q.north.c * step.s;
    q.normals[static_cast<size_t>(y)] = geo::wgs84::prime_vertical_radius(sin_lat);
  }
  q.level_error = RELIEF_TRY(terrain_.level_error(s.key));
  if (q.level_error > 0) {
    // No split makes up for the distance between the level's full mesh
    // and the finest data: a quad where that alone may exceed the threshold
    // refines to its full mesh, and the selection should split it instead.
    TerrainModel::QuadInfo* info = RELIEF_TRY(terrain_.quad(s.key));
    if (vertical_error_pixels(view_, info->box, q.bounds, q.level_error) > o_.pixel_error) {
      ++stats_.too_coarse;
      stats_.split_wanted.push_back(s.key);
      // A frame whose selection waits for data (never complete) keeps
      // such quads while their children's tiles load, often many at once
      // after a turn: their full meshes (up to 2 x 512 x 256 triangles
      // each) bought no bound and took 2 M triangles and a second a frame
      // on llvmpipe. They are refined against their own data instead.
      if (!terrain_.blocking() && selection_.stats.waiting > 0) q.level_error = 0;
    }
  }
  for (int side = 0; side < 4; ++side) {
    if ((s.coarse_sides & kSideBits[side]) && s.neighbours[static_cast<size_t>(2 * side)] >= 0) {
      q.blocking |= kSideBits[side];
    }
  }
  if (const DataWindow w = terrain_.window(s.key); w.tile) {
    q.errors = RELIEF_TRY(cache_.get(terrain_, grid_, *w.tile, stats_));
  }
  // The halves' centres (their corners are vertices: no marks).
  mark(index, {n / 2, n / 2}) = mark(index, {3 * n / 2, n / 2}) = kSplit;
  return prepare_edges(s, q);
}

// The tile of a data window (null without data).
Result<TerrainModel::TilePtr> Refiner::tile_of(const DataWindow& w) {
  if (!w.tile) return TerrainModel::TilePtr{};
  return terrain_.tile(*w.tile);
}

// Height of grid point p from a data window and its tile (0 without data).
double Refiner::height(const DataWindow& w, const TerrainModel::TilePtr& t, GridPoint p) const {
  if (!t) return 0.0;
  const double u = static_cast<double>(p.x) / (2 * grid_.n());
  const double v = static_cast<double>(p.y) / grid_.n();
  return TerrainModel::bilinear(*t, terrain_.border(), w.x0 + u * w.width, w.y0 + v * w.height);
}

// |parent - own| heights of the vertices on sides (and at corners) that take
// the coarser neighbour's data, as range-maximum tables per side.
// The last frame's when it had the same inputs (RefineCache::Impl::edges).
Status Refiner::prepare_edges(const SelectedQuad& s, Quad& q) {
  if (!s.coarse_sides && !s.coarse_corners) return {};
  const int32_t n = grid_.n();
  const DataWindow own = terrain_.window(s.key), parent = terrain_.parent_window(s.key);
  const TerrainModel::TilePtr own_tile = RELIEF_TRY(tile_of(own));
  const TerrainModel::TilePtr parent_tile = RELIEF_TRY(tile_of(parent));
  const EdgeInputs inputs{own_tile, parent_tile, own, parent, s.coarse_sides, s.coarse_corners};
  if ((q.edges = cache_.find_edges(s.key, inputs))) return {};
  auto at = [&](int side, int32_t t) {
    return side == 0   ? GridPoint{0, t}
           : side == 1 ? GridPoint{2 * n, t}
           : side == 2 ? GridPoint{t, 0}
                       : GridPoint{t, n};
  };
  std::array<std::vector<float>, 4> diff;
  auto moved = [&](GridPoint p) {
    const double d = height(parent, parent_tile, p) - height(own, own_tile, p);
    float f = static_cast<float>(std::abs(d));
    if (static_cast<double>(f) < std::abs(d)) f = std::nextafter(f, INFINITY);
    return f;
  };
  for (int side = 0; side < 4; ++side) {
    const int32_t length = side < 2 ? n : 2 * n;
    diff[side].assign(static_cast<size_t>(length) + 1, 0.0f);
    if (!(s.coarse_sides & kSideBits[side])) continue;
    for (int32_t t = 0; t <= length; t += 2) diff[side][t] = moved(at(side, t));
  }
  const struct {
    uint8_t corner;
    GridPoint p;
    int sides[2];
    int32_t t[2];
  } corners[] = {{kNorthWest, {0, 0}, {0, 2}, {0, 0}},
                 {kNorthEast, {2 * n, 0}, {1, 2}, {0, 2 * n}},
                 {kSouthWest, {0, n}, {0, 3}, {n, 0}},
                 {kSouthEast, {2 * n, n}, {1, 3}, {n, 2 * n}}};
  uint8_t used = s.coarse_sides;
  for (const auto& c : corners) {
    if (!(s.coarse_corners & c.corner)) continue;
    const float d = moved(c.p);
    for (int k = 0; k < 2; ++k) {
      diff[c.sides[k]][c.t[k]] = std::max(diff[c.sides[k]][c.t[k]], d);
      used |= kSideBits[c.sides[k]];
    }
  }
  auto edges = std::make_shared<SideEdges>();
  for (int side = 0; side < 4; ++side) {
    if (used & kSideBits[side]) edges->side[side].build(diff[side]);
  }
  q.edges = edges;
  cache_.keep_edges(s.key, inputs, std::move(edges));
  return {};
}

}  // namespace relief::lod::refinement
