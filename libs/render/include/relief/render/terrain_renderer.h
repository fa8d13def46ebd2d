#pragma once
// Draws the selected quads of an elevation store, with an imagery store draped
// over them or hypsometric colours with hillshading. One draw call per quad:
// the shared mesh topology (core + border variant), vertex positions relative
// to the eye computed in double on the CPU and converted to float, heights
// sampled from the quad's elevation tile in the vertex shader. Reversed-Z
// depth with an infinite far plane.
//
// Uses the GL context current on the calling thread; call from that thread only.
#include <array>
#include <memory>

#include "relief/base/result.h"
#include "relief/lod/selection.h"
#include "relief/render/render_target.h"

namespace relief::render {

struct RenderOptions {
  float exaggeration = 1.0f;
  std::array<float, 3> sky = {0.62f, 0.74f, 0.88f};
};

struct FrameStats {
  uint32_t draw_calls = 0;
  uint64_t triangles = 0;
  double prepare_seconds = 0;  // CPU: vertices and textures
  double gpu_seconds = 0;      // draw calls to glFinish
  // The GPU cache (L3) after the frame.
  uint32_t gpu_textures = 0, uploads = 0, gpu_evicted = 0;
  uint64_t gpu_bytes = 0, gpu_budget = 0;
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
  virtual Result<FrameStats> draw(const lod::View& view, const lod::Selection& selection,
                                  RenderTarget& target, const RenderOptions& options) = 0;
};

}  // namespace relief::render
