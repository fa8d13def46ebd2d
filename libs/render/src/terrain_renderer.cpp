#include "relief/render/terrain_renderer.h"

#include <algorithm>

#include <fmt/format.h>

#include "gl_terrain_renderer.h"
#include "terrain_capture.h"

namespace relief::render {

GlTerrainRenderer::GlTerrainRenderer(lod::TerrainModel& elevation, const tiles::Store* imagery,
                                     lod::TileProvider* imagery_tiles, uint64_t gpu_budget,
                                     int max_layers, size_t max_quads)
    : elevation_(elevation),
      imagery_(imagery),
      max_quads_(max_quads),
      slots_(gpu_budget, max_layers) {
  if (imagery_ && !imagery_tiles) {  // a still: read when needed
    owned_imagery_tiles_ = lod::blocking_provider(*imagery_, uint64_t{256} << 20);
    imagery_tiles = owned_imagery_tiles_.get();
  }
  imagery_tiles_ = imagery_tiles;
}

Result<std::unique_ptr<TerrainRenderer>> TerrainRenderer::create(lod::TerrainModel& elevation,
                                                                 const tiles::Store* imagery,
                                                                 uint64_t gpu_budget,
                                                                 lod::TileProvider* imagery_tiles) {
  if (imagery && imagery->manifest().sample_type != tiles::SampleType::UInt8) {
    return fail(imagery->root().string() + ": --imagery needs an imagery store (RGBA tiles)");
  }
  GLint max_layers = 0, max_texels = 0;
  glGetIntegerv(GL_MAX_ARRAY_TEXTURE_LAYERS, &max_layers);
  glGetIntegerv(GL_MAX_TEXTURE_BUFFER_SIZE, &max_texels);
  auto r = std::make_unique<GlTerrainRenderer>(
      elevation, imagery, imagery_tiles, gpu_budget, std::max(max_layers, 1),
      static_cast<size_t>(std::max(max_texels, 0)) * 16 / sizeof(QuadRecord));
  RELIEF_CHECK(r->init(imagery != nullptr));
  return std::unique_ptr<TerrainRenderer>(std::move(r));
}

Result<std::unique_ptr<TerrainRenderer>> TerrainRenderer::create(lod::TerrainModel& elevation,
                                                                 std::vector<TextureLayer> layers,
                                                                 uint64_t gpu_budget) {
  GLint max_layers = 0, max_texels = 0;
  glGetIntegerv(GL_MAX_ARRAY_TEXTURE_LAYERS, &max_layers);
  glGetIntegerv(GL_MAX_TEXTURE_BUFFER_SIZE, &max_texels);
  auto r = std::make_unique<GlTerrainRenderer>(
      elevation, nullptr, nullptr, gpu_budget, std::max(max_layers, 1),
      static_cast<size_t>(std::max(max_texels, 0)) * 16 / sizeof(QuadRecord));
  RELIEF_CHECK(r->init(!layers.empty()));
  RELIEF_CHECK(r->init_layers(std::move(layers)));
  return std::unique_ptr<TerrainRenderer>(std::move(r));
}

Result<ProcessOn> parse_process_on(const std::string& name) {
  if (name == "auto") return ProcessOn::automatic;
  if (name == "gpu") return ProcessOn::gpu;
  if (name == "cpu") return ProcessOn::cpu;
  return fail(fmt::format("unknown processing backend '{}' (gpu, cpu, auto)", name));
}

const char* to_string(ProcessOn where) {
  switch (where) {
    case ProcessOn::gpu:
      return "gpu";
    case ProcessOn::cpu:
      return "cpu";
    case ProcessOn::automatic:
      break;
  }
  return "auto";
}

Result<std::vector<float>> capture_positions(TerrainRenderer& renderer, const lod::View& view,
                                             const lod::Selection& selection,
                                             const RenderOptions& options,
                                             const lod::RefinedMesh* refined) {
  return static_cast<GlTerrainRenderer&>(renderer).capture(view, selection, options, refined);
}

}  // namespace relief::render
