#include "relief/lod/terrain_model.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <deque>
#include <mutex>
#include <numbers>
#include <optional>

#include <fmt/format.h>

#include "mesh_error.h"
#include "quad_map.h"
#include "relief/geo/ellipsoid.h"
#include "relief/lod/camera.h"
#include "relief/lod/screen_error.h"

namespace relief::lod {

namespace {

class NoTiles final : public TileProvider {
 public:
  bool blocking() const override { return true; }
  Result<TilePtr> get(const geo::TileKey&) override { return TilePtr{}; }
};

HeightRange unite(HeightRange a, HeightRange b) {
  return {std::min(a.lo, b.lo), std::max(a.hi, b.hi)};
}

// An axis-aligned ECEF box around the quad's surface between its lowest and
// highest heights: 5 x 5 points at both heights, padded by the bulge of the
// ellipsoid between them.
Box quad_box(const geo::TileKey& key, const HeightRange& range) {
  const geo::GeoBox b = key.bounds();
  Box box{{INFINITY, INFINITY, INFINITY}, {-INFINITY, -INFINITY, -INFINITY}};
  for (int j = 0; j <= 4; ++j) {
    for (int i = 0; i <= 4; ++i) {
      const double lon = b.west + b.width() * i / 4, lat = b.south + b.height() * j / 4;
      for (double h : {range.lo, range.hi}) {
        const Vec3 p = ecef(lon, lat, h);
        box.lo = {std::min(box.lo.x, p.x), std::min(box.lo.y, p.y), std::min(box.lo.z, p.z)};
        box.hi = {std::max(box.hi.x, p.x), std::max(box.hi.y, p.y), std::max(box.hi.z, p.z)};
      }
    }
  }
  const double step = std::max(b.width(), b.height()) / 4 * 3.14159265358979323846 / 180;
  const double pad = geo::wgs84::kSemiMajorAxis * (1 - std::cos(std::min(step, 3.14159) / 2)) + 1;
  box.lo = box.lo - Vec3{pad, pad, pad};
  box.hi = box.hi + Vec3{pad, pad, pad};
  return box;
}

}  // namespace

// Looked up two or three times per quad the selection visits, a few
// thousand quads per frame: open addressing (one cache miss, not a bucket's
// and a node's), the records in a deque so their addresses stay valid while
// the selection holds them.
struct TerrainModel::QuadCache {
  QuadMap<uint32_t> index{16384};
  std::deque<QuadInfo> infos;
  void clear() {
    index.clear();
    infos.clear();
  }
};

TerrainModel::TerrainModel(const tiles::Store* store, const MeshTopology& mesh,
                           uint64_t cache_bytes)
    : TerrainModel(store, mesh, store ? blocking_provider(*store, cache_bytes) : nullptr, nullptr) {
}

TerrainModel::TerrainModel(const tiles::Store& store, const MeshTopology& mesh,
                           TileProvider& provider)
    : TerrainModel(&store, mesh, nullptr, &provider) {
  if (!provider.blocking()) prepare_errors_on_load();
}

TerrainModel::TerrainModel(const tiles::Store* store, const MeshTopology& mesh,
                           std::unique_ptr<TileProvider> owned, TileProvider* provider)
    : store_(store),
      mesh_(mesh),
      owned_provider_(std::move(owned)),
      provider_(provider ? provider : owned_provider_.get()),
      quads_(std::make_unique<QuadCache>()) {
  if (!provider_) {  // the bare ellipsoid: no tiles at all
    owned_provider_ = std::make_unique<NoTiles>();
    provider_ = owned_provider_.get();
  }
  if (store_) {
    data_max_ = store_->manifest().max_level;
    width_ = store_->grid().width();
    height_ = store_->grid().height();
    border_ = store_->grid().border();
    sparse_ = store_->manifest().sparse_depth;
  }
  const int k = static_cast<int>(std::log2(height_));
  max_level_ = data_max_ + std::max(0, k - mesh_.refinement());
}

int TerrainModel::data_level(const geo::TileKey& key) const {
  const int top = std::min(key.level, data_max_);
  if (!sparse_) return top;
  for (int level = top; level >= 0; --level) {
    const int m = key.level - level;
    const geo::TileKey a{level, key.x >> m, key.y >> m};
    if (!store_->has_tile(a)) continue;
    if (level == top) return level;
    // The deepest tile above the quad: its data goes on below it where it
    // has no child tile; a tile with children has every child where some
    // layer has data (pipeline/fused_elevation.cpp), so not this one: no data.
    for (int c = 0; c < 4; ++c) {
      if (store_->has_tile(a.child(c & 1, c >> 1))) return top;
    }
    return level;
  }
  return top;  // no data at all: height 0, like a quad of the data's level
}

DataWindow TerrainModel::window_at(const geo::TileKey& key, int level) const {
  const int m = key.level - level;
  const geo::TileKey a{level, key.x >> m, key.y >> m};
  DataWindow w;
  if (store_ && store_->has_tile(a)) w.tile = a;
  w.width = std::ldexp(width_, -m);
  w.height = std::ldexp(height_, -m);
  w.x0 = (key.x - (a.x << m)) * w.width;
  w.y0 = (key.y - (a.y << m)) * w.height;
  return w;
}

DataWindow TerrainModel::window(const geo::TileKey& key) const {
  return window_at(key, data_level(key));
}

DataWindow TerrainModel::parent_window(const geo::TileKey& key) const {
  const int level = data_level(key);
  // Beyond a complete store's finest level, quads of every level draw the
  // finest data: it is their parent's too.
  if (level == 0 || (!sparse_ && key.level > data_max_)) return window(key);
  return window_at(key, level - 1);
}

void TerrainModel::begin_frame() {
  pinned_.clear();
  // Per-quad bounds are recomputed from the index when dropped; dropping them
  // all at once keeps a long flight's memory flat.
  if (quads_->infos.size() > kMaxCachedQuads) quads_->clear();
  if (subtree_.size() > kMaxCachedQuads) subtree_.clear();
  if (subtree_error_.size() > kMaxCachedQuads) subtree_error_.clear();
  provider_->begin_frame();
}

void TerrainModel::end_frame() {
  provider_->end_frame();
}

bool TerrainModel::available(const geo::TileKey& key) {
  if (provider_->blocking() || !store_ || !store_->has_tile(key) || pinned_.contains(key)) {
    return true;
  }
  auto tile = provider_->get(key);
  if (!tile || !*tile) return false;
  pinned_.emplace(key, std::move(*tile));
  return true;
}

Result<TerrainModel::TilePtr> TerrainModel::tile(const geo::TileKey& key) {
  if (!store_ || !store_->has_tile(key)) return TilePtr{};
  if (auto it = pinned_.find(key); it != pinned_.end()) return it->second;
  TilePtr t = RELIEF_TRY(provider_->get(key));
  // Misuse: non-blocking models draw only what available() pinned.
  assert(t && "tile() of a tile not found available() this frame");
  if (!t) return fail(fmt::format("tile {} is not resident", key.to_string()));
  return t;
}

bool TerrainModel::above_the_data(const geo::TileKey& key) const {
  return store_ && key.level < store_->manifest().min_level &&
         key.bounds().intersects(store_->manifest().extent);
}

Result<HeightRange> TerrainModel::subtree_range(const geo::TileKey& key) {
  if (auto it = subtree_.find(key); it != subtree_.end()) return it->second;
  HeightRange r{0, 0};
  if (above_the_data(key)) {  // the children's, with 0 (drawn where no child has data)
    for (int c = 0; c < 4; ++c) r = unite(r, RELIEF_TRY(subtree_range(key.child(c & 1, c >> 1))));
  } else if (store_ && key.level <= data_max_) {
    if (const tiles::IndexEntry* e = store_->index(key.level).find(key)) {
      HeightRange own{e->min, e->max};
      if (e->valid_count < static_cast<uint32_t>(width_ * height_)) own = unite(own, {0, 0});
      if (key.level == data_max_) {
        r = own;
      } else {
        bool first = true;
        for (int c = 0; c < 4; ++c) {
          const geo::TileKey child = key.child(c & 1, c >> 1);
          // Sparse depth: where a child has no tile, this tile's data goes on.
          if (sparse_ && !store_->has_tile(child)) {
            r = first ? own : unite(r, own);
          } else {
            r = first ? RELIEF_TRY(subtree_range(child))
                      : unite(r, RELIEF_TRY(subtree_range(child)));
          }
          first = false;
        }
      }
    }
  }
  subtree_[key] = r;
  return r;
}

Result<HeightRange> TerrainModel::height_range(const geo::TileKey& key) {
  const DataWindow w = window(key);
  if (!draws_ancestor(key)) return subtree_range(key);
  HeightRange r{0, 0};
  if (w.tile) {
    const TilePtr t = RELIEF_TRY(tile(*w.tile));
    const int x0 = static_cast<int>(w.x0) + border_ - 1, y0 = static_cast<int>(w.y0) + border_ - 1;
    const int x1 = static_cast<int>(w.x0 + w.width) + border_ + 1;
    const int y1 = static_cast<int>(w.y0 + w.height) + border_ + 1;
    r = {INFINITY, -INFINITY};
    const auto v = t->f32();
    for (int y = std::max(0, y0); y < std::min(t->height(), y1); ++y) {
      for (int x = std::max(0, x0); x < std::min(t->width(), x1); ++x) {
        const float h = v[static_cast<size_t>(y) * t->width() + x];
        r.lo = std::min<double>(r.lo, h);
        r.hi = std::max<double>(r.hi, h);
      }
    }
  }
  return r;
}

Result<TerrainModel::QuadInfo*> TerrainModel::quad(const geo::TileKey& key) {
  if (const uint32_t* i = quads_->index.find(key)) return &quads_->infos[*i];
  const HeightRange range = RELIEF_TRY(height_range(key));
  quads_->infos.push_back(QuadInfo{range, quad_box(key, range), area_normals(key.bounds())});
  quads_->index.set(key, static_cast<uint32_t>(quads_->infos.size() - 1));
  return &quads_->infos.back();
}

Result<double> TerrainModel::quad_error(const geo::TileKey& key, QuadInfo& info) {
  if (info.error < 0 || (info.estimated && data_resident(key))) {
    info.estimated = !data_resident(key);
    info.error = RELIEF_TRY(mesh_error(key));
  }
  return info.error;
}

bool TerrainModel::data_resident(const geo::TileKey& key) {
  const DataWindow w = window(key), p = parent_window(key);
  return (!w.tile || available(*w.tile)) && (!p.tile || available(*p.tile));
}

Result<double> TerrainModel::level_error(const geo::TileKey& key) {
  if (key.level >= data_max_ || !store_ || draws_ancestor(key)) return 0.0;
  // No data drawn where the data lies below: no bound but splitting.
  if (above_the_data(key)) return INFINITY;
  return subtree_error(key);
}

// The geometric errors of the level index (docs/store-format.md), the
// largest in the subtree: a tile whose data is narrower than a sample's
// stencil everywhere (a small dataset seen from level 0) is stored with error
// 0, its children with their real ones; taking the maximum keeps the bound
// from dropping towards the root.
double TerrainModel::subtree_error(const geo::TileKey& key) {
  if (key.level >= data_max_) return 0.0;
  if (auto it = subtree_error_.find(key); it != subtree_error_.end()) return it->second;
  double e = 0;
  if (const tiles::IndexEntry* entry = store_->index(key.level).find(key)) {
    e = entry->error;
    for (int c = 0; c < 4; ++c) e = std::max(e, subtree_error(key.child(c & 1, c >> 1)));
  }
  subtree_error_[key] = e;
  return e;
}

Result<double> TerrainModel::mesh_error(const geo::TileKey& key) {
  // Flat triangles under the curved ellipsoid: the sagitta of one square.
  const double square = 2 * std::numbers::pi / std::ldexp(1.0, key.level) / mesh_.squares_x();
  double error = geo::wgs84::kSemiMajorAxis * square * square / 8;
  if (!data_resident(key)) {
    // Only the loading of data ahead of the view asks without the tile: an
    // estimate, the error of the ancestor whose samples are as far apart as
    // this mesh's vertices (replaced by the bound once the tile is resident).
    const int coarser = std::max(0, static_cast<int>(std::log2(height_)) - mesh_.refinement());
    // (Not above the store's coarsest level: no data there, no bound.)
    const int top = store_ ? std::min(key.level, store_->manifest().min_level) : 0;
    geo::TileKey a = key;
    for (int i = 0; i < coarser && a.level > top; ++i) a = *a.parent();
    return error + RELIEF_TRY(level_error(a));
  }
  return error + RELIEF_TRY(level_error(key)) + RELIEF_TRY(exact_mesh_error(key));
}

// Sparse depth: the sides and corners of quad `key` that may take the parent
// data in a selection, where a quad touching it may draw coarser data. The
// touching quads are one level coarser at most, and a coarser quad's data
// level is never above a finer one's there: the neighbour's parent decides.
// Elsewhere a quad drawing an ancestor's window keeps its own data on every
// side, so its bound has no edge term there (splitting it would not reduce
// the term: the same two tiles at every level).
void TerrainModel::coarser_data_around(const geo::TileKey& key, uint8_t& sides,
                                       uint8_t& corners) const {
  sides = corners = 0;
  if (key.level == 0) return;
  const int own = data_level(key);
  auto lower = [&](int dx, int dy) {
    const auto n = key.neighbour(dx, dy);
    return n && data_level(*n->parent()) < own;
  };
  const bool w = lower(-1, 0), e = lower(1, 0), n = lower(0, -1), s = lower(0, 1);
  sides =
      static_cast<uint8_t>((w ? kWest : 0) | (e ? kEast : 0) | (n ? kNorth : 0) | (s ? kSouth : 0));
  corners = static_cast<uint8_t>(
      ((w || n || lower(-1, -1)) ? kNorthWest : 0) | ((e || n || lower(1, -1)) ? kNorthEast : 0) |
      ((w || s || lower(-1, 1)) ? kSouthWest : 0) | ((e || s || lower(1, 1)) ? kSouthEast : 0));
}

struct TerrainModel::PreparedErrors {
  std::mutex mutex;
  std::unordered_map<geo::TileKey, double, geo::TileKeyHash> errors;
};

// max |mesh - data| over the samples of the quad (measured by the loader's
// threads when they prepared it); above the store's finest level against the
// full mesh of the quad's data, to which level_error() adds the distance to
// the finest data. Plus the largest change of an edge vertex that takes the
// coarser parent data.
Result<double> TerrainModel::exact_mesh_error(const geo::TileKey& key) {
  const DataWindow w = window(key);
  if (!w.tile) return 0.0;
  const TilePtr t = RELIEF_TRY(tile(*w.tile));
  std::optional<double> worst;
  if (prepared_) {
    std::lock_guard lock(prepared_->mutex);
    if (auto it = prepared_->errors.find(key); it != prepared_->errors.end()) worst = it->second;
  }
  if (worst) {
    ++error_counts_.prepared;
  } else {
    worst = mesh_sample_error(mesh_, *t, border_, w, key.level < data_max_ && !draws_ancestor(key));
    ++error_counts_.measured;
  }
  // Sparse depth: a quad drawing an ancestor's data takes that tile's parent
  // on sides shared with quads of coarser data (SelectedQuad::parent_data_sides).
  if (sparse_ ? w.tile->level > 0 : key.level <= data_max_ && key.level > 0) {
    const DataWindow pw = parent_window(key);
    const TilePtr pt = pw.tile ? RELIEF_TRY(tile(*pw.tile)) : TilePtr{};
    double edge = 0;
    uint8_t sides = 0xF, corners = 0xF;
    if (sparse_) coarser_data_around(key, sides, corners);
    for (const MeshVertex& v : mesh_.vertices()) {
      if (!v.sides || !((v.sides & sides) || (v.corner & corners))) continue;
      const double own = bilinear(*t, border_, w.x0 + v.u * w.width, w.y0 + v.v * w.height);
      const double hp =
          pt ? bilinear(*pt, border_, pw.x0 + v.u * pw.width, pw.y0 + v.v * pw.height) : 0.0;
      edge = std::max(edge, std::abs(hp - own));
    }
    *worst += edge;
  }
  return *worst;
}

void TerrainModel::prepare_errors_on_load() {
  prepared_ = std::make_shared<PreparedErrors>();
  // The hook runs on the loader's threads and may outlive this model: it
  // holds copies of what it needs, never `this`.
  own_prepare_ = [prepared = prepared_, mesh = mesh_, border = border_, data_max = data_max_,
                  max_level = max_level_, width = width_,
                  height = height_](const geo::TileKey& key, const tiles::Raster& tile) {
    if (key.level > data_max) return;
    std::vector<std::pair<geo::TileKey, double>> errors;
    if (key.level < data_max) {  // the quad of the tile alone, against its full mesh
      const DataWindow w{key, 0, 0, double(width), double(height)};
      errors.emplace_back(key, mesh_sample_error(mesh, tile, border, w, true));
    }
    for (int m = 0; key.level == data_max && m <= max_level - data_max; ++m) {
      DataWindow w{key, 0, 0, std::ldexp(width, -m), std::ldexp(height, -m)};
      for (uint32_t y = 0; y < (1u << m); ++y) {
        for (uint32_t x = 0; x < (1u << m); ++x) {
          w.x0 = x * w.width;
          w.y0 = y * w.height;
          const geo::TileKey quad{key.level + m, (key.x << m) + x, (key.y << m) + y};
          errors.emplace_back(quad, mesh_sample_error(mesh, tile, border, w));
        }
      }
    }
    std::lock_guard lock(prepared->mutex);
    if (prepared->errors.size() > kMaxCachedQuads) prepared->errors.clear();
    prepared->errors.insert(errors.begin(), errors.end());
  };
  install_prepare();
}

void TerrainModel::add_prepare(TileProvider::Prepare prepare) {
  if (!prepared_) return;  // a blocking provider: frames prepare what they use
  more_prepare_.push_back(std::move(prepare));
  install_prepare();
}

void TerrainModel::skip_exact_errors_on_load() {
  if (!prepared_) return;
  own_prepare_ = nullptr;
  install_prepare();
}

void TerrainModel::install_prepare() {
  provider_->set_prepare(
      [own = own_prepare_, more = more_prepare_](const geo::TileKey& key, const tiles::Raster& t) {
        if (own) own(key, t);
        for (const TileProvider::Prepare& p : more) p(key, t);
      });
}

TerrainModel::~TerrainModel() {
  if (prepared_) provider_->set_prepare({});
}

}  // namespace relief::lod
