#pragma once
// The OpenGL TerrainRenderer (terrain_renderer.h), a class whose parts live
// in files by the pass they make:
//
//   terrain_renderer.cpp    creation, and the renderer's free functions
//   terrain_draw.cpp        the program, static buffers and GL state; drawing
//                           and capturing what a frame prepared
//   terrain_geometry.cpp    a frame prepared: per-quad records and draw
//                           commands, refined meshes' indices and grids
//   terrain_textures.cpp    elevation and imagery tiles into texture arrays
//   terrain_composites.cpp  texture layers processed and composited per quad
#include <cstdint>
#include <cstring>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "cpu_layer_processing.h"
#include "gl_backend.h"
#include "quad_records.h"
#include "relief/render/terrain_renderer.h"
#include "tile_slots.h"

namespace relief::render {

// Quad space and side/corner flags of a vertex: all a vertex holds.
struct GridVertex {
  float u, v;
  uint32_t flags;  // Side bits | Corner bits << 4
};

inline uint32_t vertex_flags(uint8_t sides, uint8_t corner) {
  return static_cast<uint32_t>(sides) | static_cast<uint32_t>(corner) << 4;
}

struct DrawCommand {  // glMultiDrawElementsIndirect's
  uint32_t count, instance_count, first_index, base_vertex, base_instance;
};

// Rewrites `buffer` with `data` unless it holds it already (`previous`);
// returns true when the buffer's storage was reallocated.
template <typename T>
bool write_if_changed(gl::Buffer& buffer, std::vector<T>& previous, const std::vector<T>& data,
                      gl::Uploads& uploads) {
  if (buffer.id() && previous.size() == data.size() &&
      std::memcmp(previous.data(), data.data(), data.size() * sizeof(T)) == 0) {
    return false;
  }
  previous = data;
  return buffer.write(data.data(), data.size() * sizeof(T), uploads);
}

class GlTerrainRenderer final : public TerrainRenderer {
 public:
  GlTerrainRenderer(lod::TerrainModel& elevation, const tiles::Store* imagery,
                    lod::TileProvider* imagery_tiles, uint64_t gpu_budget, int max_layers,
                    size_t max_quads);

  // terrain_draw.cpp
  Status init(bool draped);
  Result<FrameStats> draw(const lod::View& view, const lod::Selection& selection,
                          RenderTarget& target, const RenderOptions& o,
                          const lod::RefinedMesh* refined) override;
  Result<std::vector<float>> capture(const lod::View& view, const lod::Selection& selection,
                                     const RenderOptions& o, const lod::RefinedMesh* refined);

  // terrain_textures.cpp
  bool has_elevation_texture(const geo::TileKey& tile) const override;
  Result<FrameStats> preload_elevation(std::span<const geo::TileKey> tiles) override;
  void set_on_growth_ahead(std::function<void(uint64_t)> on_growth_ahead) override;

  // terrain_composites.cpp
  Status init_layers(std::vector<TextureLayer> layers);
  Status set_texture_layers(std::vector<TextureLayer> layers) override;
  void set_on_processed(std::function<void()> on_processed) override;

 private:
  // terrain_draw.cpp
  Status warm_up();
  void set_draw_state(const RenderOptions& o);
  void bind(gl::Program& program, const lod::View& view, const RenderOptions& o);
  uint32_t multi_draw(const lod::Selection& selection);

  // terrain_geometry.cpp
  Result<FrameStats> prepare(const lod::View& view, const lod::Selection& selection,
                             const lod::RefinedMesh* refined, bool near_to_far);
  void sort_near_to_far();
  Status check_refined(const lod::RefinedMesh& r, const lod::Selection& selection);

  // terrain_textures.cpp
  Result<std::optional<int>> height_layer(const std::optional<geo::TileKey>& key,
                                          gl::Uploads& uploads);
  Result<std::pair<lod::DataWindow, std::optional<int>>> imagery_for(const lod::SelectedQuad& quad,
                                                                     gl::Uploads& uploads);

  // terrain_composites.cpp
  Result<std::pair<lod::DataWindow, std::optional<int>>> composite_for(
      const lod::SelectedQuad& quad, gl::Uploads& uploads, FrameStats& stats);
  struct Made {
    std::optional<int> layer;  // the composite's layer in the imagery array
    bool empty = false;        // no texture layer has data at the key
  };
  Result<Made> make_composite(const geo::TileKey& a, double priority, gl::Uploads& uploads,
                              FrameStats& stats);
  Status process_view_on_cpu(const lod::Selection& selection, gl::Uploads& uploads,
                             FrameStats& stats);
  bool on_cpu(const TextureLayer& l) const;
  Result<lod::TilePtr> process_on_cpu(size_t i, const geo::TileKey& key, const lod::TilePtr& tile,
                                      double priority);

  static constexpr int kMaxGridK = 11;  // 4097 x 2049 vertices per grid
  // Seconds of processing per interactive frame (RenderOptions): a view
  // whose processing fits is complete in the first frame after a change.
  double processing_per_frame_ = 0.1;

  lod::TerrainModel& elevation_;
  const tiles::Store* imagery_;
  std::unique_ptr<lod::TileProvider> owned_imagery_tiles_;
  std::vector<TextureLayer> layers_;  // texture layers, bottom first
  std::vector<std::unique_ptr<lod::TileProvider>> owned_layer_tiles_;
  size_t reference_ = 0;             // the layer whose tiles the composites follow
  uint32_t version_ = 0;             // of the layers' parameters
  int made_this_frame_ = 0;          // composites made by the frame being prepared
  double processed_this_frame_ = 0;  // and the seconds they took
  std::unique_ptr<gpuprocess::GpuProcessor> gpu_;
  std::unique_ptr<gpuprocess::Compositor> compositor_;
  bool software_ = false;  // llvmpipe or softpipe: ProcessOn::automatic is the CPU
  std::unique_ptr<CpuLayerProcessing> cpu_;  // workers, on first use
  std::function<void()> on_processed_;       // given to cpu_
  lod::TileProvider* imagery_tiles_ = nullptr;
  size_t max_quads_;  // records in a buffer texture
  gl::Program program_, capture_program_;
  gl::VertexArray vao_;
  gl::Buffer mesh_vertices_, mesh_indices_, quad_ids_;
  std::map<int, gl::Buffer> grids_;  // refined meshes' vertex grids, by k
  gl::Buffer records_buffer_, commands_buffer_, refined_indices_;
  gl::BufferTexture records_texture_;
  std::vector<QuadRecord> records_, previous_records_;
  std::vector<DrawCommand> commands_, previous_commands_, sorted_commands_;
  std::vector<float> nearness_;  // per quad: nearness()
  std::vector<uint32_t> order_;
  std::vector<uint32_t> previous_refined_indices_;
  int refined_k_ = -1;  // the prepared frame's grid, -1: the mesh topology
  QuadRecords record_maker_;
  TileSlots slots_;
  gl::TextureArray empty_heights_{GL_R32F, GL_RED, GL_FLOAT, 4},
      empty_slopes_{GL_RG16F, GL_RG, GL_FLOAT, 8},
      empty_imagery_{GL_RGBA8, GL_RGBA, GL_UNSIGNED_BYTE, 4};
};

}  // namespace relief::render
