#pragma once
// One rank's renderer: the complete-frame path of view::Scene (every tile
// read before drawing, so frames are deterministic), split in two so a rank
// can draw a part of a frame. select() chooses and refines the quads of the
// whole view, exactly as one process would (sort-last: every rank refines
// the whole selection, with the same result), or of one window of it
// (sort-first, walls: a rank reads only what its part shows; refinement at
// the window's edges may differ from the whole view's, within the same error
// bound); draw() draws the quads a mask keeps, through the whole view or one
// of its windows. The union of the ranks' parts is the whole frame.
//
// Needs a current GL context; used on its thread only.
#include <memory>
#include <optional>
#include <span>
#include <vector>

#include "relief/base/result.h"
#include "relief/lod/camera.h"
#include "relief/lod/refine.h"
#include "relief/lod/selection.h"
#include "relief/parallel/decompose.h"
#include "relief/render/render_target.h"
#include "relief/render/terrain_renderer.h"
#include "relief/view/scene.h"

namespace relief::parallel {

class FrameRenderer {
 public:
  // `elevation` and `imagery` (may be null) must outlive the renderer;
  // `options.interactive` is ignored (frames are complete).
  static Result<std::unique_ptr<FrameRenderer>> create(const tiles::Store& elevation,
                                                       const tiles::Store* imagery,
                                                       const view::SceneOptions& options);
  ~FrameRenderer();

  // Selects (and refines) the quads of `view`: the whole view, or only what
  // its window shows (lod::select_quads), measured as the whole view does.
  Status select(const lod::View& view);
  const lod::Selection& selection() const { return selection_; }
  const lod::RefinedMesh* refined() const { return refined_ ? &*refined_ : nullptr; }
  // Triangles of each selected quad.
  std::vector<uint64_t> quad_triangles() const;
  // Whether a quad's triangles can be drawn in part (edge-mark meshes, one
  // index range per quad), so rank_triangles may split quads.
  bool splits_quads() const { return refined_.has_value(); }
  // The selected quads that can reach `view`'s window, whole (conservative:
  // their bounding boxes meet its sub-frustum); all of them without a window.
  Result<std::vector<TriangleRange>> quads_in_window(const lod::View& view);

  // Draws parts[i] of each selected quad i through `view` (the selected view,
  // or it with a window) into `target` (the window's size).
  Result<render::FrameStats> draw(const lod::View& view, std::span<const TriangleRange> parts,
                                  render::RenderTarget& target);

 private:
  FrameRenderer(const tiles::Store& elevation, const view::SceneOptions& options);
  bool edge_marks() const;
  view::SceneOptions options_;
  lod::MeshTopology mesh_;
  std::unique_ptr<lod::TerrainModel> terrain_;
  std::unique_ptr<render::TerrainRenderer> renderer_;
  std::unique_ptr<lod::RefineCache> refine_cache_;
  lod::Selection selection_;
  std::optional<lod::RefinedMesh> refined_;
};

}  // namespace relief::parallel
