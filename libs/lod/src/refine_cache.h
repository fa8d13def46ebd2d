#pragma once
// What RefineCache keeps between frames (refine.h): the diamond errors of
// data tiles, measured once per tile (diamond_errors.h) on the render thread
// or the loader's, and the side heights of the last frame's quads.
#include <cstdint>
#include <list>
#include <memory>
#include <mutex>
#include <unordered_map>
#include <vector>

#include "diamond_errors.h"
#include "edge_marks.h"
#include "relief/lod/refine.h"
#include "side_edges.h"

namespace relief::lod {

// The grid of every quad of a store (its tiles' width: 2n cells of half a sample).
MarkGrid grid_of(const TerrainModel& terrain);

// What a quad's side heights (SideEdges) were computed from.
struct EdgeInputs {
  TilePtr own_tile, parent_tile;  // held: compared by address
  DataWindow own, parent;
  uint8_t coarse_sides = 0, coarse_corners = 0;

  bool operator==(const EdgeInputs& o) const;
};

struct RefineCache::Impl {
  std::mutex mutex;  // the render thread and the loader's threads
  uint64_t budget = 0, bytes = 0;
  std::list<geo::TileKey> lru;  // most recent first
  uint64_t frame = 1;           // counts end_frame()
  struct Entry {
    std::shared_ptr<const DiamondErrors> errors;
    std::list<geo::TileKey>::iterator at;
    bool prepared = false;  // off the render thread, not used by a frame yet
    uint64_t used = 0;      // the frame that last used it, or in which it was made
  };
  std::unordered_map<geo::TileKey, Entry, geo::TileKeyHash> entries;
  // The side heights of the last frame's quads (Refiner::prepare_edges: a
  // few hundred bilinear heights and a range table per quad, a tenth of a
  // fast camera's refinement when made every frame), and this frame's.
  struct Edges {
    EdgeInputs inputs;
    std::shared_ptr<const SideEdges> edges;
  };
  std::unordered_map<geo::TileKey, Edges, geo::TileKeyHash> last_edges, edges;

  // The side heights made from the same inputs this frame or the last (null:
  // none), kept for the next frame as this frame's.
  std::shared_ptr<const SideEdges> find_edges(const geo::TileKey& key, const EdgeInputs& in);
  void keep_edges(const geo::TileKey& key, const EdgeInputs& in,
                  std::shared_ptr<const SideEdges> e);
  // What the next frame may reuse: this frame's.
  // The errors of every tile the frame held count as used, not only the
  // refined quads' own: a parent tile a frame draws coarse sides with, or
  // one selection checked, would otherwise be forgotten and loaded again
  // frame after frame.
  void end_frame(const TerrainModel& terrain);

  // Evicts least recently used errors over the budget, except level 0's (kept,
  // as the loader keeps its tiles) and those the last two frames used or
  // that were made since (mutex held). Evicting those made the render thread
  // measure them again (the loaders' tiles pushing out the view's); the
  // budget may be exceeded by them (a view's tiles, a few hundred at most).
  // The tiles whose errors were evicted are forgotten by the provider
  // (TileProvider::forget): a view that wants one again loads it again, and
  // the loader's threads prepare it, instead of the render thread measuring it.
  void evict_over_budget(std::vector<geo::TileKey>& evicted);

  bool contains(const geo::TileKey& key);

  // Adds the errors of `key`. Nothing is evicted here but at the end of a
  // frame, on the render thread, once the tiles the frame held are marked
  // used: a loader's thread evicting in the middle of a frame could take the
  // errors of a tile that frame is about to refine.
  void put(const geo::TileKey& key, std::shared_ptr<const DiamondErrors> errors, bool prepared);

  // The errors of the diamonds of data tile `key`, counted in `stats` when
  // a frame uses them for the first time.
  Result<std::shared_ptr<const DiamondErrors>> get(TerrainModel& terrain, const MarkGrid& grid,
                                                   const geo::TileKey& key, RefineStats& stats);
};

}  // namespace relief::lod
