#pragma once
// Level-of-detail selection (seed 003 §1.4.2): walk the quadtree from level 0,
// bound each quad from metadata and cached error bounds, cull by the frustum
// and by the ellipsoid's horizon, split a quad while its mesh error projected
// at its nearest point exceeds the pixel-error threshold (or, up to the data's
// finest level, while its samples are coarser than pixels), then enforce the
// restricted property (quads sharing an edge or a corner differ by at most one
// level), which makes the meshes conform.
#include <array>
#include <cstdint>
#include <functional>
#include <vector>

#include "relief/base/result.h"
#include "relief/lod/camera.h"
#include "relief/lod/terrain_model.h"

namespace relief::lod {

// How the mesh of a selected quad is made: the fixed MeshTopology, quads
// split down to virtual levels where every sample is a vertex; or edge-mark
// refinement of each quad's own grid (seed 003 ch. 3, lod/refine.h), quads
// going no deeper than the data.
enum class LodMode { quads, edge_marks };

struct SelectionOptions {
  double pixel_error = 1.0;  // largest allowed screen-space error, pixels
  LodMode mode = LodMode::quads;
  // Edge marks: a quad splits while the distance of its level's full mesh to
  // the finest data (TerrainModel::level_error) projects to more than this
  // share of pixel_error; the refinement inside it has the rest.
  double level_error_share = 0.5;
  // A draped texture (imagery store), or null. Where the elevation data or
  // the texture has a tile, a quad also splits while one of its samples
  // covers more than a pixel (seed 003 §1.4.2, step 5).
  const tiles::Store* texture = nullptr;
  // Every quad with data at the deepest level instead, nothing else (with a
  // mesh of one vertex per sample: the brute-force reference).
  bool full_resolution = false;
  size_t max_quads = 200000;
  // The deepest level split to (< 0: the terrain's max_level()); edge-mark
  // refinement (refine.h) wants the store's finest, data_max_level().
  int max_level = -1;
  // Quads to split even when their bound does not ask for it (as far as
  // their data allows): those the refinement of earlier frames wanted split
  // (lod/split_feedback.h). Null: none.
  std::function<bool(const geo::TileKey&)> also_split;
  // Fill SelectedQuad::neighbours (for consumers that walk the mesh on the
  // GPU, like the seed's refinement); costs ~0.3 ms per 2000 quads.
  bool neighbour_indices = false;
  // Interactive frames: whether a resident data tile may be drawn by this
  // frame (a budget of tiles uploaded to the GPU per frame, view/scene.h).
  // A quad splits only when the tiles of its visible children may be drawn;
  // otherwise it stays whole this frame (SelectionStats::deferred), as it
  // does while they load. Null: every resident tile.
  std::function<bool(const geo::TileKey& tile)> drawable_now;
};

struct SelectedQuad {
  geo::TileKey key;
  uint8_t finer_sides = 0;     // Side bits: neighbours one level finer (split border triangles)
  uint8_t coarse_sides = 0;    // Side bits: neighbours one level coarser (take parent data)
  uint8_t coarse_corners = 0;  // Corner bits: a quad sharing the corner is coarser
  // Where the vertices' heights take the parent data (TerrainModel::parent_window):
  // the coarse sides and corners, or, for a store of sparse depth, those where
  // a quad touching them draws coarser data (TerrainModel::data_level), whatever
  // its level. The positions follow coarse_sides/corners.
  uint8_t parent_data_sides = 0, parent_data_corners = 0;
  double error_pixels = 0;  // the bound that stopped the split
  double priority = 0;      // view priority of loading its data (interactive frames only)
  // Indices into Selection::quads of the neighbours across each side, two per
  // side (west, east, north, south): both set when the side has two finer
  // neighbours, the first alone otherwise; -1 where there is none on screen.
  // Filled when SelectionOptions::neighbour_indices is set.
  std::array<int32_t, 8> neighbours{-1, -1, -1, -1, -1, -1, -1, -1};
};

struct SelectionStats {
  std::vector<uint32_t> quads_per_level;
  uint64_t triangles = 0;
  uint32_t quads = 0;
  uint32_t culled = 0;
  double seconds = 0;
  double max_error_pixels = 0;
  // Interactive frames: quads drawn coarser than wanted because the data of
  // their children is not resident yet (it was requested).
  uint32_t waiting = 0;
  // Interactive frames: children's tiles resident but not drawn by this frame
  // (SelectionOptions::drawable_now); a later frame draws them.
  uint32_t deferred = 0;
};

struct Selection {
  std::vector<SelectedQuad> quads;  // visible leaves, in no particular order
  SelectionStats stats;
};

// The quads `view` shows; a view with a window (camera.h) culls to its window
// but measures errors as the whole view does.
Result<Selection> select_quads(const View& view, TerrainModel& terrain,
                               const SelectionOptions& options);

// The restricted quadtree over the whole globe that `split` (quad -> split
// it?) asks for, then restricted like a selection: for tests and tools.
Result<Selection> restricted_quadtree(TerrainModel& terrain,
                                      const std::function<bool(const geo::TileKey&)>& split);

// Whether the point is hidden behind the ellipsoid (shrunk by `below` metres)
// seen from the eye.
bool below_horizon(const Vec3& eye, const Vec3& point, double below);

}  // namespace relief::lod
