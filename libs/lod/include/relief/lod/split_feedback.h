#pragma once
// Quads the edge-mark refinement of a frame wanted split
// (RefineStats::split_wanted: the coarser quads whose sides stopped a split
// where the criterion wanted it, and the quads whose level error alone
// projects over the threshold), fed back into the selection of the next
// frames (SelectionOptions::also_split), so the unresolved diamonds of one
// frame are resolved in the next.
//
// A wanted quad stays split while the eye is no more than twice as far from
// it as when it was wanted: a static view keeps its splits (it does not
// flicker between two meshes), a view moving away lets them go (the error
// they resolved projects to about half as many pixels by then; should it
// still be over the threshold, the refinement wants the quad again).
#include <functional>
#include <optional>
#include <unordered_map>

#include "relief/geo/tile_key.h"
#include "relief/lod/camera.h"
#include "relief/lod/refined_mesh.h"
#include "relief/lod/terrain_model.h"

namespace relief::lod {

class SplitFeedback {
 public:
  // Records the quads a frame of `view` wanted split.
  void record(const View& view, TerrainModel& terrain, const RefineStats& stats);
  // Whether a selection of `view` should split `key` (forgets it if not).
  bool wanted(const View& view, TerrainModel& terrain, const geo::TileKey& key);
  // The predicate for SelectionOptions::also_split; `view`, `terrain` and
  // this must outlive the selection that uses it.
  std::function<bool(const geo::TileKey&)> for_selection(const View& view, TerrainModel& terrain);
  size_t size() const { return distance_.size(); }
  void clear() { distance_.clear(); }

 private:
  // Quads above this are forgotten at once (those no selection reached again).
  static constexpr size_t kMaxQuads = 100000;
  std::unordered_map<geo::TileKey, double, geo::TileKeyHash> distance_;  // the eye's, when wanted
};

}  // namespace relief::lod
