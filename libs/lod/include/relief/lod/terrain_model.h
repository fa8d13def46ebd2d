#pragma once
// What level-of-detail selection and rendering need to know about the terrain
// of a quad: its data tile, a conservative height range, and an upper bound
// on the vertical distance between the quad's mesh and the finest data.
//
// Quads go deeper than the store: beyond its finest level they draw a part of
// the finest tile with the same mesh, down to the level where every finest
// sample is a vertex (max_level()). Absent tiles and nodata are height 0 (the
// ellipsoid).
#include <memory>
#include <optional>
#include <unordered_map>
#include <vector>

#include "relief/base/result.h"
#include "relief/lod/data_window.h"
#include "relief/lod/mesh_topology.h"
#include "relief/lod/screen_error.h"
#include "relief/lod/tile_provider.h"
#include "relief/lod/vec.h"
#include "relief/tiles/store.h"

namespace relief::lod {

struct HeightRange {
  double lo = 0, hi = 0;
};

// Used by one thread at a time (the render thread): its caches are not locked.
class TerrainModel {
 public:
  // `store` may be null (the bare ellipsoid). Tiles are read when needed and
  // decoded tiles cached within `cache_bytes` (complete frames).
  TerrainModel(const tiles::Store* store, const MeshTopology& mesh, uint64_t cache_bytes);
  // Tiles come from `provider` (which must outlive the model); with a
  // non-blocking one, selection draws only what is resident (interactive frames).
  TerrainModel(const tiles::Store& store, const MeshTopology& mesh, TileProvider& provider);
  ~TerrainModel();
  TerrainModel(const TerrainModel&) = delete;
  TerrainModel& operator=(const TerrainModel&) = delete;

  const MeshTopology& mesh() const { return mesh_; }
  const tiles::Store* store() const { return store_; }  // null: the bare ellipsoid
  int data_max_level() const { return data_max_; }
  int max_level() const { return max_level_; }
  int tile_width() const { return width_; }
  int tile_height() const { return height_; }
  int border() const { return border_; }

  // The data tile and window of quad `key`; at or above the store's finest
  // level the tile is the quad itself. Stores of sparse depth
  // (Manifest::sparse_depth, fused layers of different depths): the quad's
  // tile, or else its deepest ancestor tile if that has no child tile (where
  // a tile has no child, its data goes on below it; a tile with children has
  // them wherever there is data, so below a missing one there is none).
  DataWindow window(const geo::TileKey& key) const;
  // The window of the quad's parent data, for vertices on sides shared with a
  // coarser quad: the parent's tile (or, beyond the store, the same tile).
  // Sparse depth: the parent of the tile the quad draws, for sides shared
  // with quads of coarser data.
  DataWindow parent_window(const geo::TileKey& key) const;
  // The level of the data quad `key` draws (window()'s tile's): its own level
  // up to the store's finest; for sparse depth the ancestor tile's it draws.
  int data_level(const geo::TileKey& key) const;
  // Whether the quad draws a window of an ancestor tile (beyond the finest
  // level, or below a leaf of a store of sparse depth), not a tile of its own.
  bool draws_ancestor(const geo::TileKey& key) const { return data_level(key) < key.level; }
  bool sparse_depth() const { return sparse_; }

  // Frames: between begin_frame() and the next one, every tile found
  // available() stays pinned (resident), so selection and drawing see the
  // same data. begin_frame() also drops per-quad caches above their budget.
  void begin_frame();
  void end_frame();
  // Whether tiles load on demand (complete frames) or only resident ones may
  // be used (interactive frames).
  bool blocking() const { return provider_->blocking(); }
  // Whether the data tile `key` can be used now without waiting (always for
  // blocking providers and for tiles the store does not have).
  bool available(const geo::TileKey& key);
  // Ask for a tile that was not available, with its view priority.
  void request(const geo::TileKey& key, double priority) { provider_->request(key, priority); }
  // Where tiles come from (for TileProvider::forget, from any thread).
  TileProvider& provider() const { return *provider_; }

  // Decoded bordered tile with nodata as 0, or nullptr when the store has
  // none. Non-blocking providers: only for tiles found available() this frame.
  using TilePtr = lod::TilePtr;
  Result<TilePtr> tile(const geo::TileKey& key);
  // The tiles this frame found available (and holds until the next begin).
  template <class F>
  void for_each_held(F f) const {
    for (const auto& entry : pinned_) f(entry.first);
  }

  // Everything selection asks about a quad, cached per quad: the heights of
  // the terrain in it (plus one sample around), an ECEF box around its
  // surface between them, and the mesh error bound, measured on first use
  // (it may load the quad's tile): see quad_error.
  struct QuadInfo {
    HeightRange range;
    Box box;
    AreaNormals normals;     // of the quad's area (the angle bounds' trigonometry)
    double error = -1;       // < 0: not measured yet
    bool estimated = false;  // the quad's data was not resident: an estimate
  };
  Result<QuadInfo*> quad(const geo::TileKey& key);
  Result<double> quad_error(const geo::TileKey& key, QuadInfo& info);

  // Upper bound, metres, of the vertical distance between the full mesh of
  // quad `key`'s level data (every sample a vertex) and the finest data below
  // it, from the level index's geometric errors (the largest in the subtree):
  // 0 at and beyond the store's finest level. Needs no tiles.
  Result<double> level_error(const geo::TileKey& key);

  // Bilinear height at interior sample coordinates (x, y) of a bordered tile,
  // exactly as the renderer's vertex shader computes it (data_window.h).
  static float bilinear(const tiles::Raster& bordered, int border, double x, double y) {
    return bilinear_height(bordered, border, x, y);
  }

  // Exact errors of quads at and below the store's finest level: how many
  // were measured on this (the render) thread and how many came prepared by
  // the loader's threads (non-blocking providers).
  struct ErrorCounts {
    uint64_t measured = 0, prepared = 0;
  };
  ErrorCounts error_counts() const { return error_counts_; }

  // More work for each freshly decoded tile on the loader's threads, after
  // the model's own exact errors (non-blocking providers; nothing otherwise):
  // refine.h's diamond errors. The hook may outlive this model and its
  // caller: it must hold what it uses (copies, weak pointers).
  void add_prepare(TileProvider::Prepare prepare);
  // The loader's threads stop measuring the quads' exact errors (quad_error)
  // of each decoded tile: for interactive frames meshed by edge-mark
  // refinement, whose selection never asks for them (a frame that does
  // measures them on its own thread, as for blocking providers).
  void skip_exact_errors_on_load();

 private:
  // Per-quad bounds kept between frames (~200 bytes each).
  static constexpr size_t kMaxCachedQuads = 200000;
  TerrainModel(const tiles::Store* store, const MeshTopology& mesh,
               std::unique_ptr<TileProvider> owned, TileProvider* provider);
  Result<HeightRange> height_range(const geo::TileKey& key);
  DataWindow window_at(const geo::TileKey& key, int level) const;
  void coarser_data_around(const geo::TileKey& key, uint8_t& sides, uint8_t& corners) const;
  // Whether the data the quad draws is resident: its tile and, for its sides
  // shared with a coarser quad, its parent's (or there are none).
  bool data_resident(const geo::TileKey& key);
  // Upper bound, in metres, of |mesh - finest data| over the quad, including
  // the chord error of flat triangles on the curved ellipsoid.
  Result<double> mesh_error(const geo::TileKey& key);
  Result<HeightRange> subtree_range(const geo::TileKey& key);
  double subtree_error(const geo::TileKey& key);
  // A quad above the store's coarsest level (relief build --min-level) over
  // its data: it has no tile, the data lies below it.
  bool above_the_data(const geo::TileKey& key) const;
  Result<double> exact_mesh_error(const geo::TileKey& key);
  // Has the provider measure the exact errors of every quad of a finest tile
  // on its own threads when it decodes the tile.
  void prepare_errors_on_load();

  // Installs the model's own work and every add_prepare() hook as one.
  void install_prepare();

  struct PreparedErrors;  // shared with the provider's threads

  const tiles::Store* store_;
  const MeshTopology& mesh_;
  int data_max_ = 0, max_level_ = 0, width_ = 512, height_ = 256, border_ = 0;
  bool sparse_ = false;  // Manifest::sparse_depth
  std::unique_ptr<TileProvider> owned_provider_;
  TileProvider* provider_;
  std::unordered_map<geo::TileKey, TilePtr, geo::TileKeyHash> pinned_;  // this frame's
  std::unordered_map<geo::TileKey, HeightRange, geo::TileKeyHash> subtree_;
  std::unordered_map<geo::TileKey, double, geo::TileKeyHash> subtree_error_;
  struct QuadCache;  // per-quad bounds: stable addresses, open addressing
  std::unique_ptr<QuadCache> quads_;
  std::shared_ptr<PreparedErrors> prepared_;  // null: blocking provider
  TileProvider::Prepare own_prepare_;
  std::vector<TileProvider::Prepare> more_prepare_;
  ErrorCounts error_counts_;
};

}  // namespace relief::lod
