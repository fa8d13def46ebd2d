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
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "relief/base/result.h"
#include "relief/gpuprocess/chain.h"
#include "relief/gpuprocess/composite.h"
#include "relief/lod/refined_mesh.h"
#include "relief/lod/selection.h"
#include "relief/render/render_target.h"

namespace relief::render {

struct RenderOptions {
  float exaggeration = 1.0f;
  std::array<float, 3> sky = {0.62f, 0.74f, 0.88f};
  bool wireframe = false;  // the triangles' edges instead of filled triangles (the LOD panel)
  // Seconds of texture-layer processing an interactive frame may spend; past
  // it the rest is made by the next frames (ancestors meanwhile). 100 ms is
  // the latency issue 14 asks of a parameter change. Tests that step frames
  // deterministically set it to infinity (the budget reads the steady clock).
  double processing_per_frame = 0.1;
  // draw() returns once the GL has drawn the frame (glFinish; gpu_seconds
  // measures it). False: once the draw calls are issued and flushed, so the
  // caller works while the GL draws (the viewer, docs/viewer.md "Overlap");
  // gpu_seconds is then submit_seconds.
  bool finish = true;
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
  // Of gpu_seconds: issuing the draw calls (llvmpipe shades vertices and bins
  // triangles on the calling thread; its own threads rasterise after).
  double submit_seconds = 0;
  // The GPU cache (L3) after the frame: resident tiles, their bytes, tiles
  // uploaded and evicted by this frame, layers allocated in the texture
  // arrays (slots, resident or free) and their bytes.
  uint32_t gpu_textures = 0, uploads = 0, gpu_evicted = 0, gpu_slots = 0;
  uint64_t gpu_bytes = 0, gpu_budget = 0, gpu_allocated_bytes = 0;
  // Texture layers: layer tiles processed by this frame (through their
  // chains, composited), the seconds that took on the GPU (to glFinish), and
  // the quads drawn with an ancestor's composite or none while theirs waits
  // for a tile (a frame with any is not complete).
  uint32_t layer_tiles_processed = 0, texture_misses = 0;
  double processing_seconds = 0;
  // Layers processed on the CPU (ProcessOn::cpu): the seconds the frame
  // waited for the workers to finish the view's tiles (within the budget).
  double processing_wait_seconds = 0;
};

// A texture layer draped over the terrain (docs/gpu-processing.md,
// "Draw-time processing"): a store's tiles through an operator chain, mapped
// through [range_min, range_max] and a colour map (single-band stores; RGBA
// imagery is drawn as it is), composited by opacity in the order given.
// A lens over a texture layer (seed 003 §1.5.2): inside the circle (centre in
// degrees, radius in metres on the ground) the layer's samples go through
// `chain` (parameters for the store's finest level) instead of the layer's;
// quads the edge crosses are processed by both and merged sample by sample.
struct Lens {
  double lon = 0, lat = 0, radius_m = 0;
  gpuprocess::OperatorChain chain;
};

// Where a single-band layer's chain runs (docs/gpu-processing.md, "Where
// layers are processed"): on the GPU (GpuProcessor), or with the CPU
// reference (run_chain_cpu) on worker threads, the result uploaded and then
// mapped and composited on the GPU. Automatic: the CPU on a software
// renderer (llvmpipe, softpipe: the CPU kernels are 4-25x faster there),
// the GPU otherwise. Layers with lenses are processed on the GPU.
enum class ProcessOn { automatic, gpu, cpu };
// "auto", "gpu" or "cpu"; anything else is a one-line error.
Result<ProcessOn> parse_process_on(const std::string& name);
const char* to_string(ProcessOn where);

struct TextureLayer {
  const tiles::Store* store = nullptr;
  // Where tiles come from: a non-blocking provider for interactive frames
  // (missing tiles are requested, ancestors shown meanwhile); null: read when
  // needed.
  lod::TileProvider* tiles = nullptr;
  // Parameters for the store's finest level; coarser tiles get
  // gpuprocess::scale_chain's, so masks keep their size on the ground.
  gpuprocess::OperatorChain chain;
  float range_min = 0, range_max = 1;
  gpuprocess::ColorMap colormap = gpuprocess::ColorMap::grey;
  float opacity = 1;
  std::vector<Lens> lenses;  // single-band layers
  ProcessOn process_on = ProcessOn::automatic;
};

// Whether a layer can be drawn: chain valid for the store (kind, border,
// statistics), range_min < range_max, opacity in [0, 1], lenses of a positive
// radius with valid chains on a single-band store. One-line errors.
Status check_texture_layer(const TextureLayer& layer);

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
  // With texture layers instead of one imagery store, composited per quad on
  // the GPU (needs GL 4.5); the finest layer's store (the first of
  // equally fine ones) sets the composites' tiles and their size.
  static Result<std::unique_ptr<TerrainRenderer>> create(lod::TerrainModel& elevation,
                                                         std::vector<TextureLayer> layers,
                                                         uint64_t gpu_budget = uint64_t{1} << 30);
  virtual ~TerrainRenderer() = default;
  // New layer parameters (same stores, count and order of layers as given to
  // create()), from the next draw() on: no composite made with the old ones is
  // drawn again.
  virtual Status set_texture_layers(std::vector<TextureLayer> layers) = 0;
  // Draws `selection`, with the elevation model's mesh topology or, when
  // `refined` is given (parallel to selection.quads), its triangles.
  virtual Result<FrameStats> draw(const lod::View& view, const lod::Selection& selection,
                                  RenderTarget& target, const RenderOptions& options,
                                  const lod::RefinedMesh* refined = nullptr) = 0;
  // Called on a worker thread each time a texture-layer tile processed on
  // the CPU for an interactive frame is ready (a later frame draws it).
  // Set before the first draw().
  virtual void set_on_processed(std::function<void()> on_processed) = 0;
  // Called on the render thread with the bytes the next growth of a texture
  // array of the GPU cache will allocate, once per size, when it draws near
  // (TileSlots::set_on_growth_ahead): time to make that memory ready.
  virtual void set_on_growth_ahead(std::function<void(uint64_t bytes)> on_growth_ahead) = 0;
  // Whether an elevation tile's heights are on the GPU: drawing a quad of it
  // uploads nothing (the budget of new tiles per frame, view/scene.h).
  virtual bool has_elevation_texture(const geo::TileKey& tile) const = 0;
  // Uploads those of `tiles` (resident in the elevation model) that are not
  // on the GPU yet, whether this frame draws them or not: FrameStats::uploads,
  // texture_bytes and prepare_seconds say what it did. Call it where draw() may be called
  // (its uploads wait for the GL to be done with the previous frame).
  virtual Result<FrameStats> preload_elevation(std::span<const geo::TileKey> tiles) = 0;
};

}  // namespace relief::render
