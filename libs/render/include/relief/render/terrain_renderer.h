#pragma once
// Draws the selected quads of an elevation store, with an imagery store draped
// over them or hypsometric colours with hillshading. Geometry lives on the
// GPU: static vertex and index buffers of quad-space (u, v) (the shared mesh
// topology, core + border variants, or the vertex grids of refined meshes),
// one small record per quad (its corners relative to the eye, computed in
// double on the CPU, its data windows and texture layers), and the data tiles
// as layers of texture arrays under the GPU budget (L3). The vertex shader
// builds each position relative to a corner of its quad in float and samples
// its height; all quads go in one multi-draw-indirect call. A view that does
// not change uploads nothing. Reversed-Z depth with an infinite far
// plane.
//
// Uses the GL context current on the calling thread; call from that thread only.
#include <array>
#include <memory>

#include "relief/base/result.h"
#include "relief/lod/refined_mesh.h"
#include "relief/lod/selection.h"
#include "relief/render/render_target.h"

namespace relief::render {

struct RenderOptions {
  float exaggeration = 1.0f;
  std::array<float, 3> sky = {0.62f, 0.74f, 0.88f};
  bool wireframe = false;  // the triangles' edges instead of filled triangles (the LOD panel)
};

struct FrameStats {
  uint32_t draw_calls = 0;  // GL draw calls (each a multi-draw of many quads)
  uint32_t quads = 0;       // quads drawn
  uint64_t triangles = 0;
  uint64_t pixels = 0;  // of the target
  double triangles_per_pixel() const {
    return pixels ? static_cast<double>(triangles) / static_cast<double>(pixels) : 0.0;
  }
  // Bytes this frame copied to the GPU: geometry (vertices, indices, per-quad
  // records, draw commands) and tile textures.
  uint64_t geometry_bytes = 0, texture_bytes = 0;
  double prepare_seconds = 0;  // CPU: records, textures and uploads
  double gpu_seconds = 0;      // draw calls to glFinish
  // The GPU cache (L3) after the frame: resident tiles, their bytes, tiles
  // uploaded and evicted by this frame, layers allocated in the texture
  // arrays (slots, resident or free) and their bytes.
  uint32_t gpu_textures = 0, uploads = 0, gpu_evicted = 0, gpu_slots = 0;
  uint64_t gpu_bytes = 0, gpu_budget = 0, gpu_allocated_bytes = 0;
};

class TerrainRenderer {
 public:
  // `imagery` may be null. Both must outlive the renderer. Tile textures are
  // kept within `gpu_budget` bytes, except those the current frame draws.
  // Imagery tiles come from `imagery_tiles` when given (a non-blocking one
  // for interactive frames: quads whose imagery is not resident show their
  // nearest resident ancestor's, and the tile is requested during draw()),
  // otherwise they are read when needed.
  static Result<std::unique_ptr<TerrainRenderer>> create(
      lod::TerrainModel& elevation, const tiles::Store* imagery,
      uint64_t gpu_budget = uint64_t{1} << 30, lod::TileProvider* imagery_tiles = nullptr);
  virtual ~TerrainRenderer() = default;
  // Draws `selection`, with the elevation model's mesh topology or, when
  // `refined` is given (parallel to selection.quads), its triangles.
  virtual Result<FrameStats> draw(const lod::View& view, const lod::Selection& selection,
                                  RenderTarget& target, const RenderOptions& options,
                                  const lod::RefinedMesh* refined = nullptr) = 0;
};

}  // namespace relief::render
