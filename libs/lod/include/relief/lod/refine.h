#pragma once
// Edge-mark refinement (seed 003 ch. 3), the CPU reference: the quads of a
// restricted-quadtree selection refined into one conforming triangulation of
// right isosceles triangles by a per-diamond screen-space split criterion on
// the actual samples, down to the full mesh of each quad's level (every
// sample cell cut by its diagonals). Two variants giving the same mesh:
// top-down (from four triangles per quad half, splitting with forced splits
// propagated across quads of equal and different levels: seed Fig. 3.8) and
// bottom-up (every edge mark of every quad decided, finest first: Fig. 3.6).
//
// The criterion splits a diamond D (a triangle pair) while
//   vertical_error_pixels(view, box(D), area(D),
//                         err(D) + level_error(quad) + edge(D) + sagitta(D)) > t,
// where err(D) bounds |D's two triangles - the level's full mesh| over D
// (measured once per data tile, diamond_errors.h), level_error that full mesh's
// distance to the finest data, edge(D) how far vertices on a side shared with
// a coarser quad move by taking the parent's data, sagitta(D) the chord error
// of flat triangles on the ellipsoid. So every finest sample projects within t
// pixels of the mesh, except where a quad meets a coarser one: there a sample
// cell's side cannot be split (the coarser quad has no vertex there), and what
// the criterion would still want is counted in RefineStats::unresolved (the
// selection should then split the coarser quad).
#include <cstdint>
#include <memory>

#include "relief/base/parallel.h"
#include "relief/base/result.h"
#include "relief/lod/camera.h"
#include "relief/lod/refined_mesh.h"
#include "relief/lod/selection.h"
#include "relief/lod/terrain_model.h"

namespace relief::lod {

class CriterionEvaluator;

enum class RefineVariant : uint8_t { kTopDown, kBottomUp };

// Per-diamond errors of data tiles (about 2 MB per tile of 512 x 256), kept
// between frames within a byte budget: at the end of each frame the least
// recently used go, but never level 0's (kept, as a loader keeps its tiles)
// or those of tiles the last two frames held (so the budget may be exceeded
// by a view's tiles). For one store. refine() measures the tiles it misses
// on its own (the render) thread; with prepare_on_load(), the loader's
// threads fill it too (it is locked), and the provider forgets the tiles
// whose errors were evicted (TileProvider::forget), so that they load and
// are prepared again instead of being measured by a frame.
class RefineCache {
 public:
  explicit RefineCache(uint64_t budget_bytes = uint64_t{512} << 20);
  ~RefineCache();
  RefineCache(const RefineCache&) = delete;
  RefineCache& operator=(const RefineCache&) = delete;
  uint64_t bytes() const;
  size_t tiles() const;

  // Interactive frames: the diamond errors of every tile `terrain`'s
  // non-blocking provider decodes are measured on the loader's threads before
  // the tile becomes resident, and those of the tiles already resident (level
  // 0, loaded at creation) now, so refine() never measures a tile on the
  // render thread unless the budget dropped it while the tile was held
  // (otherwise the tile is forgotten with its errors). Byte for byte the errors
  // refine() would measure. Nothing for a blocking model (complete frames
  // measure inline). The cache and the model may go in either order.
  void prepare_on_load(TerrainModel& terrain);

  struct Impl;
  Impl& impl() { return *impl_; }

 private:
  std::shared_ptr<Impl> impl_;  // shared with the loader's threads
};

// What the last frames decided per quad, for the next frame to reuse where
// the camera moved too little to change any decision (refine_reuse.cpp;
// docs/rendering.md, "Reusing decisions"): the mesh is the one refinement
// without history computes, at a fraction of the cost. One per sequence of
// frames of one terrain (a scene), used by one thread at a time.
class RefineHistory {
 public:
  RefineHistory();
  ~RefineHistory();
  RefineHistory(const RefineHistory&) = delete;
  RefineHistory& operator=(const RefineHistory&) = delete;
  void clear();

  struct Impl;
  Impl& impl() { return *impl_; }

 private:
  std::unique_ptr<Impl> impl_;
};

struct RefineOptions {
  double pixel_error = 1.0;  // largest allowed screen-space error, pixels
  RefineVariant variant = RefineVariant::kTopDown;
  // Top-down: the quads refined by as many lanes as its concurrency, on its
  // threads (the same mesh; RefineStats::marks_evaluated then counts a
  // diamond on a side between two lanes' quads once per lane that reached
  // it). Null, or bottom-up: on the calling thread.
  Executor* executor = nullptr;
  RefineCache* cache = nullptr;      // null: a cache for this call only
  RefineHistory* history = nullptr;  // null: every quad decided from scratch
  // Every diamond's criterion evaluated at once by this (a GL compute shader:
  // render::GlRefineCriteria) before the refinement, which then looks the
  // decisions up and evaluates only those too near the threshold: the same
  // mesh, either variant. It evaluates every diamond, as bottom-up does.
  // With it, `history` is not used (a recorded decision's margins need the
  // CPU's own terms). Null: the criteria are evaluated here, as reached.
  CriterionEvaluator* criteria = nullptr;
};

// Needs a selection made with SelectionOptions::neighbour_indices, of quads no
// deeper than the store's finest level (terrain.data_max_level()): the grid
// of such a quad already reaches every sample.
Result<RefinedMesh> refine(const View& view, TerrainModel& terrain, const Selection& selection,
                           const RefineOptions& options);

}  // namespace relief::lod
