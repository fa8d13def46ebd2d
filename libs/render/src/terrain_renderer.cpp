#include "relief/render/terrain_renderer.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <map>
#include <numeric>
#include <set>

#include <fmt/format.h>

#include "cpu_layer_processing.h"
#include "gl_backend.h"
#include "quad_records.h"
#include "shaders.h"
#include "terrain_capture.h"
#include "tile_slots.h"

namespace relief::render {
namespace {

using geo::TileKey;
using Clock = std::chrono::steady_clock;

// Quad space and side/corner flags of a vertex: all a vertex holds.
struct GridVertex {
  float u, v;
  uint32_t flags;  // Side bits | Corner bits << 4
};

struct DrawCommand {  // glMultiDrawElementsIndirect's
  uint32_t count, instance_count, first_index, base_vertex, base_instance;
};

// Rotation-only view (the eye is the origin) times a reversed-Z projection
// with an infinite far plane: depth = near / distance, 1 at the near plane.
void view_projection(const lod::View& v, float out[16]) {
  const double f = 1.0 / v.tan_half_y, aspect = static_cast<double>(v.width) / v.height;
  // Column-major. Row i of the view matrix: right, up, -forward.
  const lod::Vec3 rows[3] = {v.right, v.up, -v.forward};
  double view[16] = {};
  for (int r = 0; r < 3; ++r) {
    view[0 * 4 + r] = rows[r].x;
    view[1 * 4 + r] = rows[r].y;
    view[2 * 4 + r] = rows[r].z;
  }
  view[15] = 1;
  double proj[16] = {};
  proj[0] = f / aspect;
  proj[5] = f;
  proj[11] = -1;      // w = -z_view
  proj[14] = v.near;  // z = near
  for (int c = 0; c < 4; ++c) {
    for (int r = 0; r < 4; ++r) {
      double s = 0;
      for (int k = 0; k < 4; ++k) s += proj[k * 4 + r] * view[c * 4 + k];
      out[c * 4 + r] = static_cast<float>(s);
    }
  }
}

uint32_t vertex_flags(uint8_t sides, uint8_t corner) {
  return static_cast<uint32_t>(sides) | static_cast<uint32_t>(corner) << 4;
}

// The vertex grid of refined meshes at level k (lod/refined_mesh.h).
std::vector<GridVertex> refined_grid(int k) {
  const uint32_t nx = 2u << k, ny = 1u << k;
  std::vector<GridVertex> out(static_cast<size_t>(nx + 1) * (ny + 1));
  for (uint32_t j = 0; j <= ny; ++j) {
    for (uint32_t i = 0; i <= nx; ++i) {
      uint8_t s = 0, c = 0;
      if (i == 0) s |= lod::kWest;
      if (i == nx) s |= lod::kEast;
      if (j == 0) s |= lod::kNorth;
      if (j == ny) s |= lod::kSouth;
      if ((s & lod::kNorth) && (s & lod::kWest)) c = lod::kNorthWest;
      if ((s & lod::kNorth) && (s & lod::kEast)) c = lod::kNorthEast;
      if ((s & lod::kSouth) && (s & lod::kWest)) c = lod::kSouthWest;
      if ((s & lod::kSouth) && (s & lod::kEast)) c = lod::kSouthEast;
      out[lod::grid_vertex_id(k, i, j)] = {static_cast<float>(i) / static_cast<float>(nx),
                                           static_cast<float>(j) / static_cast<float>(ny),
                                           vertex_flags(s, c)};
    }
  }
  return out;
}

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
                    size_t max_quads)
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

  // Texture layers (the other create()): composited per quad on the GPU.
  Status init_layers(std::vector<TextureLayer> layers) {
    if (layers.empty()) return {};
    gpu_ = RELIEF_TRY(gpuprocess::GpuProcessor::create());
    compositor_ = RELIEF_TRY(gpuprocess::Compositor::create());
    const char* name = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
    const std::string renderer = name ? name : "";
    software_ = renderer.find("llvmpipe") != std::string::npos ||
                renderer.find("softpipe") != std::string::npos;
    for (size_t i = 0; i < layers.size(); ++i) {
      if (layers[i].store->manifest().max_level > layers[reference_].store->manifest().max_level) {
        reference_ = i;
      }
    }
    owned_layer_tiles_.resize(layers.size());
    return set_texture_layers(std::move(layers));
  }

  void set_on_growth_ahead(std::function<void(uint64_t)> on_growth_ahead) override {
    slots_.set_on_growth_ahead(std::move(on_growth_ahead));
  }

  void set_on_processed(std::function<void()> on_processed) override {
    on_processed_ = std::move(on_processed);
  }

  bool has_elevation_texture(const TileKey& tile) const override {
    return slots_.contains({tile, false});
  }

  Result<FrameStats> preload_elevation(std::span<const TileKey> tiles) override {
    const auto start = Clock::now();
    FrameStats stats;
    gl::Uploads uploads;
    const uint64_t before = slots_.uploads();
    for (const TileKey& tile : tiles) {
      if (!slots_.contains({tile, false})) RELIEF_TRY(height_layer(tile, uploads));
    }
    stats.uploads = static_cast<uint32_t>(slots_.uploads() - before);
    stats.texture_bytes = uploads.textures;
    stats.prepare_seconds = std::chrono::duration<double>(Clock::now() - start).count();
    return stats;
  }

  Status set_texture_layers(std::vector<TextureLayer> layers) override {
    if (layers.size() != layers_.size() && !layers_.empty()) {
      return fail(
          fmt::format("{} texture layers given, the scene has {}", layers.size(), layers_.size()));
    }
    for (size_t i = 0; i < layers.size(); ++i) {
      RELIEF_CHECK(check_texture_layer(layers[i]));
      if (!layers_.empty() && layers[i].store != layers_[i].store) {
        return fail(fmt::format("texture layer {}: its store cannot change", i + 1));
      }
      if (!layers[i].tiles) {  // a still: read when needed
        if (!owned_layer_tiles_[i]) {
          owned_layer_tiles_[i] = lod::blocking_provider(*layers[i].store, uint64_t{256} << 20);
        }
        layers[i].tiles = owned_layer_tiles_[i].get();
      }
    }
    layers_ = std::move(layers);
    ++version_;  // composites of the old parameters are never drawn again
    if (cpu_) cpu_->drop_before(version_);
    return {};
  }

  // `draped`: imagery or texture layers will be drawn (the fragment shader's variant).
  Status init(bool draped) {
    program_ = RELIEF_TRY(gl::Program::link(kTerrainVertexShader, fragment_shader(draped).c_str()));
    const lod::MeshTopology& mesh = elevation_.mesh();
    std::vector<GridVertex> vertices;
    for (const lod::MeshVertex& v : mesh.vertices())
      vertices.push_back({v.u, v.v, vertex_flags(v.sides, v.corner)});
    gl::Uploads setup;
    mesh_vertices_ =
        gl::Buffer::make_static(vertices.data(), vertices.size() * sizeof(GridVertex), setup);
    mesh_indices_ = gl::Buffer::make_static(mesh.indices().data(),
                                            mesh.indices().size() * sizeof(uint32_t), setup);
    vao_.attribute(0, 0, 2, GL_FLOAT, offsetof(GridVertex, u));
    vao_.attribute(1, 0, 1, GL_UNSIGNED_INT, offsetof(GridVertex, flags));
    vao_.attribute(2, 1, 1, GL_UNSIGNED_INT, 0);
    glVertexArrayBindingDivisor(vao_.id(), 1, 1);
    // Per quad: its record's fields that do not depend on the corner (shaders.h).
    vao_.attribute(3, 2, 4, GL_FLOAT, offsetof(QuadRecord, own_window));
    vao_.attribute(4, 2, 4, GL_FLOAT, offsetof(QuadRecord, parent_window));
    vao_.attribute(5, 2, 4, GL_FLOAT, offsetof(QuadRecord, imagery_window));
    vao_.attribute(6, 2, 4, GL_FLOAT, offsetof(QuadRecord, size));
    vao_.attribute(7, 2, 4, GL_UNSIGNED_INT, offsetof(QuadRecord, slots));
    vao_.attribute(8, 2, 1, GL_FLOAT, offsetof(QuadRecord, shade));
    glVertexArrayBindingDivisor(vao_.id(), 2, 1);
    // Bound where a kind has no tiles yet.
    const float zero[4] = {};
    for (gl::TextureArray* a : {&empty_heights_, &empty_slopes_, &empty_imagery_}) {
      a->set_layer_size(1, 1);
      a->reserve(1);
      a->upload(0, zero, setup);
    }
    // The arrays' first layers, before the first frame (TileSlots::allocate).
    if (const tiles::Store* s = elevation_.store()) {
      slots_.allocate(false, s->grid().padded_width(), s->grid().padded_height());
    }
    if (imagery_) {
      slots_.allocate(true, imagery_->grid().padded_width(), imagery_->grid().padded_height());
    }
    if (auto e = gl_error(); !e.empty()) return fail("renderer setup: " + e);
    return warm_up();
  }

  // llvmpipe compiles a program's machine code for the GL state of its first
  // draw (12 ms and more here): one draw now, of a triangle that covers
  // nothing, with the frames' state and the elevation's texture formats, so
  // that the first frame of a view or a flight does not stall on it (a later
  // state, e.g. the first composites' array, may still compile once). The
  // buffers it writes are rewritten by the first frame.
  Status warm_up() {
    auto target = RELIEF_TRY(make_offscreen_target(1, 1));
    records_.assign(1, QuadRecord{});
    commands_.assign(1, DrawCommand{3, 1, 0, 0, 0});
    gl::Uploads ignored;
    if (write_if_changed(records_buffer_, previous_records_, records_, ignored)) {
      records_texture_.attach(records_buffer_);
    }
    write_if_changed(commands_buffer_, previous_commands_, commands_, ignored);
    const uint32_t id = 0;
    quad_ids_ = gl::Buffer::make_static(&id, sizeof id, ignored);
    lod::View view;
    view.right = {1, 0, 0}, view.up = {0, 1, 0}, view.forward = {0, 0, -1};
    view.width = view.height = 1;
    view.tan_half_x = view.tan_half_y = 1;
    target->bind();
    set_draw_state(RenderOptions{});
    bind(program_, view, RenderOptions{});
    glMultiDrawElementsIndirect(GL_TRIANGLES, GL_UNSIGNED_INT, nullptr, 1, 0);
    glFinish();
    if (auto e = gl_error(); !e.empty()) return fail("renderer warm-up: " + e);
    return {};
  }

  void set_draw_state(const RenderOptions& o) {
    glClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_GREATER);
    glEnable(GL_CULL_FACE);
    glCullFace(GL_BACK);
    glFrontFace(GL_CCW);
    glClearColor(o.sky[0], o.sky[1], o.sky[2], 1);
    glClearDepth(0);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  }

  Result<FrameStats> draw(const lod::View& view, const lod::Selection& selection,
                          RenderTarget& target, const RenderOptions& o,
                          const lod::RefinedMesh* refined) override {
    const auto start = Clock::now();
    processing_per_frame_ = o.processing_per_frame;
    FrameStats stats = RELIEF_TRY(prepare(view, selection, refined, true));
    stats.prepare_seconds = std::chrono::duration<double>(Clock::now() - start).count();
    stats.pixels = static_cast<uint64_t>(target.width()) * static_cast<uint64_t>(target.height());

    const lod::PixelRect& w = view.window;
    if (!w.empty() && (target.width() != w.width || target.height() != w.height)) {
      return fail(fmt::format("a {}x{} window drawn into a {}x{} target", w.width, w.height,
                              target.width(), target.height()));
    }
    const auto gpu_start = Clock::now();
    target.bind();
    // A window of the view: the whole view's viewport, shifted so the window
    // lands on the target. The projection stays the whole view's, so every
    // vertex reaches the same clip coordinates as in the whole image and the
    // windows of a view assemble into exactly its image.
    if (!w.empty()) glViewport(-w.x, w.y + w.height - view.height, view.width, view.height);
    set_draw_state(o);
    bind(program_, view, o);
    glPolygonMode(GL_FRONT_AND_BACK, o.wireframe ? GL_LINE : GL_FILL);
    stats.draw_calls = multi_draw(selection);
    glPolygonMode(GL_FRONT_AND_BACK, GL_FILL);
    glFlush();  // llvmpipe's threads rasterise from here
    stats.submit_seconds = std::chrono::duration<double>(Clock::now() - gpu_start).count();
    if (o.finish) glFinish();
    stats.gpu_seconds = std::chrono::duration<double>(Clock::now() - gpu_start).count();
    if (auto e = gl_error(); !e.empty()) return fail("drawing: " + e);
    return stats;
  }

  Result<std::vector<float>> capture(const lod::View& view, const lod::Selection& selection,
                                     const RenderOptions& o, const lod::RefinedMesh* refined) {
    processing_per_frame_ = o.processing_per_frame;
    const FrameStats stats = RELIEF_TRY(prepare(view, selection, refined, false));
    if (!capture_program_.id()) {
      capture_program_ = RELIEF_TRY(
          gl::Program::link(kTerrainVertexShader, kTerrainFragmentShader, {"captured_position"}));
    }
    const size_t bytes = stats.triangles * 3 * 3 * sizeof(float);
    gl::Buffer out;
    gl::Uploads ignored;
    std::vector<float> positions(stats.triangles * 9);
    out.write(positions.data(), bytes, ignored);
    auto target = RELIEF_TRY(make_offscreen_target(1, 1));  // draws need a complete framebuffer
    target->bind();
    glEnable(GL_RASTERIZER_DISCARD);
    glBindBufferRange(GL_TRANSFORM_FEEDBACK_BUFFER, 0, out.id(), 0, static_cast<GLsizeiptr>(bytes));
    bind(capture_program_, view, o);
    glBeginTransformFeedback(GL_TRIANGLES);
    multi_draw(selection);
    glEndTransformFeedback();
    glDisable(GL_RASTERIZER_DISCARD);
    glGetNamedBufferSubData(out.id(), 0, static_cast<GLsizeiptr>(bytes), positions.data());
    if (auto e = gl_error(); !e.empty()) return fail("capturing: " + e);
    return positions;
  }

 private:
  // Records, draw commands and textures of a frame, on the GPU; uploads only
  // what differs from the previous frame. Draw commands nearest quad first
  // when `near_to_far`, else in the selection's order (captures).
  Result<FrameStats> prepare(const lod::View& view, const lod::Selection& selection,
                             const lod::RefinedMesh* refined, bool near_to_far) {
    if (selection.quads.size() > max_quads_) {
      return fail(
          fmt::format("{} quads in a frame, more than the {} the GPU's buffer textures hold",
                      selection.quads.size(), max_quads_));
    }
    if (refined) RELIEF_CHECK(check_refined(*refined, selection));
    FrameStats stats;
    gl::Uploads uploads;
    slots_.begin_frame();
    made_this_frame_ = 0;
    processed_this_frame_ = 0;
    if (cpu_) cpu_->begin_frame();
    if (!layers_.empty()) RELIEF_CHECK(process_view_on_cpu(selection, uploads, stats));
    const uint64_t uploads_before = slots_.uploads(), evicted_before = slots_.evicted();
    const lod::MeshTopology& mesh = elevation_.mesh();
    records_.clear();
    commands_.clear();
    nearness_.clear();
    for (size_t q = 0; q < selection.quads.size(); ++q) {
      const lod::SelectedQuad& quad = selection.quads[q];
      QuadRecord r = record_maker_.make(quad, view.eye);
      const lod::DataWindow own = elevation_.window(quad.key),
                            parent = elevation_.parent_window(quad.key);
      if (auto layer = RELIEF_TRY(height_layer(own.tile, uploads))) {
        r.slots[0] = static_cast<uint32_t>(*layer), r.slots[3] |= kHasOwn;
      }
      if (auto layer = RELIEF_TRY(height_layer(parent.tile, uploads))) {
        r.slots[1] = static_cast<uint32_t>(*layer), r.slots[3] |= kHasParent;
      }
      const auto [imagery_window, imagery_layer] = RELIEF_TRY(
          layers_.empty() ? imagery_for(quad, uploads) : composite_for(quad, uploads, stats));
      if (imagery_layer)
        r.slots[2] = static_cast<uint32_t>(*imagery_layer), r.slots[3] |= kHasImagery;
      auto window = [](float out[4], const lod::DataWindow& w) {
        out[0] = static_cast<float>(w.x0), out[1] = static_cast<float>(w.y0);
        out[2] = static_cast<float>(w.width), out[3] = static_cast<float>(w.height);
      };
      window(r.own_window, own);
      window(r.parent_window, parent);
      window(r.imagery_window, imagery_window);
      // North-south spacing of the data tile's samples (the quad's, or its ancestor's).
      const double spacing_deg = quad.key.bounds().height() / own.height;
      r.shade[0] = static_cast<float>(spacing_deg * 3.14159265358979323846 / 180 * 6371000.0);
      records_.push_back(r);
      DrawCommand c{0, 1, 0, 0, static_cast<uint32_t>(q)};
      if (refined) {
        c.count = refined->quads[q].index_count;
        c.first_index = refined->quads[q].first_index;
      } else {
        c.count = mesh.index_count(quad.finer_sides);
        c.first_index = mesh.first_index(quad.finer_sides);
      }
      commands_.push_back(c);
      nearness_.push_back(nearness(r));
      stats.triangles += c.count / 3;
    }
    if (near_to_far) sort_near_to_far();
    if (write_if_changed(records_buffer_, previous_records_, records_, uploads)) {
      records_texture_.attach(records_buffer_);
    }
    write_if_changed(commands_buffer_, previous_commands_, commands_, uploads);
    const size_t ids_held = quad_ids_.size() / sizeof(uint32_t);
    if (ids_held < selection.quads.size()) {  // grows only
      std::vector<uint32_t> ids(std::max(selection.quads.size(), 2 * ids_held));
      std::iota(ids.begin(), ids.end(), 0u);
      quad_ids_ = gl::Buffer::make_static(ids.data(), ids.size() * sizeof(uint32_t), uploads);
    }
    if (refined) {
      auto [grid, fresh] = grids_.try_emplace(refined->grid_k);
      if (fresh) {
        const std::vector<GridVertex> v = refined_grid(refined->grid_k);
        grid->second = gl::Buffer::make_static(v.data(), v.size() * sizeof(GridVertex), uploads);
      }
      write_if_changed(refined_indices_, previous_refined_indices_, refined->indices, uploads);
    }
    refined_k_ = refined ? refined->grid_k : -1;

    stats.quads = static_cast<uint32_t>(selection.quads.size());
    stats.geometry_bytes = uploads.geometry;
    stats.texture_bytes = uploads.textures;
    stats.gpu_textures = static_cast<uint32_t>(slots_.count());
    stats.gpu_bytes = slots_.used_bytes();
    stats.gpu_budget = slots_.budget_bytes();
    stats.gpu_slots = static_cast<uint32_t>(slots_.slots());
    stats.gpu_allocated_bytes = slots_.allocated_bytes();
    stats.uploads = static_cast<uint32_t>(slots_.uploads() - uploads_before);
    stats.gpu_evicted = static_cast<uint32_t>(slots_.evicted() - evicted_before);
    return stats;
  }

  // Draw commands nearest quad first (by nearness()): llvmpipe tests depth
  // before shading a block of pixels, so pixels behind terrain already drawn
  // cost no shading (the order does not change the image: the depth test
  // keeps the nearest fragment whatever the order).
  void sort_near_to_far() {
    order_.resize(commands_.size());
    std::iota(order_.begin(), order_.end(), 0u);
    std::stable_sort(order_.begin(), order_.end(),
                     [&](uint32_t a, uint32_t b) { return nearness_[a] < nearness_[b]; });
    sorted_commands_.clear();
    for (uint32_t i : order_) sorted_commands_.push_back(commands_[i]);
    commands_.swap(sorted_commands_);
  }

  // A refined mesh the GPU can draw without reading outside its buffers.
  Status check_refined(const lod::RefinedMesh& r, const lod::Selection& selection) {
    if (r.quads.size() != selection.quads.size()) {
      return fail(fmt::format("refined mesh: {} quads for a selection of {}", r.quads.size(),
                              selection.quads.size()));
    }
    if (r.grid_k < 0 || r.grid_k > kMaxGridK) {
      return fail(fmt::format("refined mesh: grid level {} outside 0..{}", r.grid_k, kMaxGridK));
    }
    for (const lod::RefinedQuad& q : r.quads) {
      if (q.index_count % 3 || q.first_index > r.indices.size() ||
          q.index_count > r.indices.size() - q.first_index) {
        return fail(fmt::format("refined mesh: indices [{}, +{}) of a quad outside 0..{}",
                                q.first_index, q.index_count, r.indices.size()));
      }
    }
    // Indices are checked when they change (they are uploaded then), or their grid.
    const bool same = r.grid_k == refined_k_ &&
                      previous_refined_indices_.size() == r.indices.size() &&
                      std::memcmp(previous_refined_indices_.data(), r.indices.data(),
                                  r.indices.size() * sizeof(uint32_t)) == 0;
    const uint32_t vertices = r.grid_columns() * r.grid_rows();
    if (!same && std::any_of(r.indices.begin(), r.indices.end(),
                             [&](uint32_t i) { return i >= vertices; })) {
      return fail(fmt::format("refined mesh: a vertex id past the {} of grid level {}", vertices,
                              r.grid_k));
    }
    return {};
  }

  // Binds everything prepare() made.
  void bind(gl::Program& program, const lod::View& view, const RenderOptions& o) {
    glUseProgram(program.id());
    glBindVertexArray(vao_.id());
    const bool refined = refined_k_ >= 0;
    glVertexArrayVertexBuffer(vao_.id(), 0,
                              refined ? grids_.at(refined_k_).id() : mesh_vertices_.id(), 0,
                              sizeof(GridVertex));
    glVertexArrayVertexBuffer(vao_.id(), 1, quad_ids_.id(), 0, sizeof(uint32_t));
    glVertexArrayVertexBuffer(vao_.id(), 2, records_buffer_.id(), 0, sizeof(QuadRecord));
    glVertexArrayElementBuffer(vao_.id(), refined ? refined_indices_.id() : mesh_indices_.id());
    glBindTextureUnit(2, records_texture_.id());
    glBindBuffer(GL_DRAW_INDIRECT_BUFFER, commands_buffer_.id());
    glBindTextureUnit(0, slots_.heights().layers() ? slots_.heights().id() : empty_heights_.id());
    glBindTextureUnit(1, slots_.imagery().layers() ? slots_.imagery().id() : empty_imagery_.id());
    glBindTextureUnit(3, slots_.slopes().layers() ? slots_.slopes().id() : empty_slopes_.id());
    float vp[16];
    view_projection(view, vp);
    glUniformMatrix4fv(program.location("view_projection"), 1, GL_FALSE, vp);
    glUniform1i(program.location("heights"), 0);
    glUniform1i(program.location("imagery"), 1);
    glUniform1i(program.location("records"), 2);
    glUniform1i(program.location("slopes"), 3);
    glUniform1i(program.location("border"), elevation_.border());
    // Composites keep a one-sample border (Compositor::composite).
    glUniform1i(program.location("imagery_border"), !layers_.empty() ? 1
                                                    : imagery_       ? imagery_->manifest().border
                                                                     : 0);
    glUniform1f(program.location("exaggeration"), o.exaggeration);
  }

  // Draws every quad prepare() made, one draw command each; returns the draw calls.
  uint32_t multi_draw(const lod::Selection& selection) {
    if (selection.quads.empty()) return 0;
    glMultiDrawElementsIndirect(GL_TRIANGLES, GL_UNSIGNED_INT, nullptr,
                                static_cast<GLsizei>(selection.quads.size()), 0);
    return 1;
  }

  // The texture layer of an elevation tile, uploaded when it arrives;
  // nullopt where there is no data.
  Result<std::optional<int>> height_layer(const std::optional<TileKey>& key, gl::Uploads& uploads) {
    if (!key) return std::optional<int>();
    if (auto layer = slots_.find({*key, false})) return layer;
    const lod::TerrainModel::TilePtr tile = RELIEF_TRY(elevation_.tile(*key));
    if (!tile) return std::optional<int>();
    return std::optional<int>(RELIEF_TRY(
        slots_.insert({*key, false}, tile->width(), tile->height(), tile->f32().data(), uploads)));
  }

  // The imagery of a quad: the layer of the imagery tile at the quad's level
  // (or the imagery's finest), else of its nearest ancestor whose texture or
  // decoded tile is at hand (non-blocking providers: the wanted tile is
  // requested meanwhile). Colour has no cracks to fear, so any ancestor will do.
  Result<std::pair<lod::DataWindow, std::optional<int>>> imagery_for(const lod::SelectedQuad& quad,
                                                                     gl::Uploads& uploads) {
    lod::DataWindow w;
    std::optional<int> layer;
    if (!imagery_) return std::pair{w, layer};
    const TileKey& key = quad.key;
    const int finest = std::min(key.level, imagery_->manifest().max_level);
    int m = key.level - finest;
    for (TileKey a{finest, key.x >> m, key.y >> m};; a = *a.parent(), ++m) {
      if (imagery_->has_tile(a)) {
        if (auto l = slots_.find({a, true})) {
          layer = l;
        } else if (const lod::TilePtr tile = RELIEF_TRY(imagery_tiles_->get(a))) {
          // premultiplied by decode_tile
          layer = RELIEF_TRY(
              slots_.insert({a, true}, tile->width(), tile->height(), tile->u8().data(), uploads));
        } else if (a.level == finest) {
          imagery_tiles_->request(a, quad.priority);
        }
        if (layer) {
          w.tile = a;
          w.width = std::ldexp(imagery_->grid().width(), -m);
          w.height = std::ldexp(imagery_->grid().height(), -m);
          w.x0 = (key.x - (a.x << m)) * w.width;
          w.y0 = (key.y - (a.y << m)) * w.height;
          break;
        }
      }
      if (a.level == 0) break;
    }
    return std::pair{w, layer};
  }

  // The composite of a quad's texture layers: that of its tile at the
  // reference layer's finest level or above, else (its layers' tiles not at
  // hand yet: requested) of its nearest ancestor whose tiles are, made now if
  // not cached for the current parameters. Never one of older parameters.
  Result<std::pair<lod::DataWindow, std::optional<int>>> composite_for(
      const lod::SelectedQuad& quad, gl::Uploads& uploads, FrameStats& stats) {
    lod::DataWindow w;
    std::optional<int> layer;
    const TileKey& key = quad.key;
    const tiles::Store& ref = *layers_[reference_].store;
    const int finest = std::min(key.level, ref.manifest().max_level);
    int m = key.level - finest;
    bool wanted = false;  // the quad draws its own composite, or needs none
    for (TileKey a{finest, key.x >> m, key.y >> m};; a = *a.parent(), ++m) {
      // Missing ancestors' tiles are requested too (at a lower priority): the
      // quad shows something while its own load; coarse tiles are few and shared.
      const double priority = a.level == finest ? quad.priority : quad.priority * 0.5;
      const Made made = RELIEF_TRY(make_composite(a, priority, uploads, stats));
      if (made.empty || made.layer) wanted = a.level == finest;
      if (made.empty) break;  // no layer has data here: the terrain's own colours
      if ((layer = made.layer)) {
        w.tile = a;
        w.width = std::ldexp(ref.grid().width(), -m);
        w.height = std::ldexp(ref.grid().height(), -m);
        w.x0 = (key.x - (a.x << m)) * w.width;
        w.y0 = (key.y - (a.y << m)) * w.height;
        break;
      }
      if (a.level == 0) break;
    }
    if (!wanted) ++stats.texture_misses;  // an ancestor's, or nothing, while tiles load
    return std::pair{w, layer};
  }

  struct Made {
    std::optional<int> layer;  // the composite's layer in the imagery array
    bool empty = false;        // no texture layer has data at the key
  };

  // The composite of texture key `a` for the current parameters: cached, or
  // made from the layers' tiles when every one is at hand (otherwise those
  // missing are requested, and nothing is made).
  Result<Made> make_composite(const TileKey& a, double priority, gl::Uploads& uploads,
                              FrameStats& stats) {
    Made made;
    if (auto l = slots_.find({a, true, version_})) {
      made.layer = l;
      return made;
    }
    std::vector<lod::TilePtr> tiles(layers_.size());
    std::vector<TileKey> keys(layers_.size());
    bool any = false, missing = false, interactive = false;
    for (size_t i = 0; i < layers_.size(); ++i) {
      interactive = interactive || !layers_[i].tiles->blocking();
      const tiles::Store& store = *layers_[i].store;
      const tiles::Manifest& man = store.manifest();
      const int level = std::min(a.level, man.max_level);
      if (level < man.min_level) continue;
      const int up = a.level - level;
      keys[i] = TileKey{level, a.x >> up, a.y >> up};
      if (!store.has_tile(keys[i])) continue;
      any = true;
      tiles[i] = RELIEF_TRY(layers_[i].tiles->get(keys[i]));
      if (!tiles[i]) {
        missing = true;
        layers_[i].tiles->request(keys[i], priority);
      }
    }
    made.empty = !any;
    if (!any || missing) return made;
    // Layers processed on the CPU: their results, or the jobs submitted.
    std::vector<lod::TilePtr> processed(layers_.size());
    bool pending = false;
    for (size_t i = 0; i < layers_.size(); ++i) {
      if (!tiles[i] || !on_cpu(layers_[i])) continue;
      processed[i] = RELIEF_TRY(process_on_cpu(i, keys[i], tiles[i], priority));
      pending = pending || !processed[i];
    }
    if (pending) return made;  // an ancestor's composite meanwhile
    // Interactive frames do not wait for processing either: past a budget of
    // processing time, the rest are made by the next frames (ancestors
    // meanwhile). A time budget, not a count: cheap chains finish a view in
    // one frame, costly ones keep frames short.
    if (interactive && made_this_frame_ > 0 && processed_this_frame_ >= processing_per_frame_) {
      return made;
    }
    // What the GL still has to do first (llvmpipe rasterises the previous
    // frame's draws when something waits for them) is not processing.
    if (made_this_frame_ == 0) glFinish();
    ++made_this_frame_;
    const auto start = Clock::now();
    const tiles::Store& ref = *layers_[reference_].store;
    const int width = ref.grid().width() + 2, height = ref.grid().height() + 2;
    if (layers_.size() == 1 && processed[0] &&
        processed[0]->type() == tiles::SampleType::UInt8) {  // colours made on the CPU
      made.layer = RELIEF_TRY(
          slots_.insert({a, true, version_}, width, height, processed[0]->u8().data(), uploads));
      if (cpu_) cpu_->forget({0, keys[0], version_});
      ++stats.layer_tiles_processed;
      const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
      stats.processing_seconds += seconds;
      processed_this_frame_ += seconds;
      return made;
    }
    const int slot =
        RELIEF_TRY(slots_.insert({a, true, version_}, width, height, nullptr, uploads));
    std::vector<gpuprocess::OperatorChain> chains(layers_.size());
    std::vector<std::vector<gpuprocess::OperatorChain>> lens_chains(layers_.size());
    std::vector<std::vector<gpuprocess::CompositeLens>> lenses(layers_.size());
    std::vector<process::GlobalStats> global(layers_.size());
    std::vector<gpuprocess::CompositeLayer> inputs;
    for (size_t i = 0; i < layers_.size(); ++i) {
      if (!tiles[i]) continue;
      const TextureLayer& l = layers_[i];
      const tiles::Manifest& man = l.store->manifest();
      const double factor = std::ldexp(1.0, man.max_level - keys[i].level);
      chains[i] = gpuprocess::scale_chain(l.chain, factor);
      for (const Lens& lens : l.lenses) {
        lens_chains[i].push_back(gpuprocess::scale_chain(lens.chain, factor));
      }
      for (size_t j = 0; j < l.lenses.size(); ++j) {
        lenses[i].push_back(
            {&lens_chains[i][j], l.lenses[j].lon, l.lenses[j].lat, l.lenses[j].radius_m});
      }
      global[i] = {man.stats.min, man.stats.max, man.stats.mean, man.stats.stddev};
      const int up = a.level - keys[i].level;
      const double tw = std::ldexp(l.store->grid().width(), -up),
                   th = std::ldexp(l.store->grid().height(), -up);
      gpuprocess::CompositeLayer c;
      c.tile = tiles[i].get();
      c.border = man.border;
      c.chain = &chains[i];
      if (processed[i]) {  // the chain ran on the CPU: the result, as it is
        c.tile = processed[i].get();
        c.border = 1;
        c.chain = nullptr;
      }
      c.stats = &global[i];
      c.range_min = l.range_min, c.range_max = l.range_max;
      c.colormap = l.colormap;
      c.opacity = l.opacity;
      c.window = {(a.x - (keys[i].x << up)) * tw, (a.y - (keys[i].y << up)) * th, tw, th};
      c.lenses = lenses[i];
      c.bounds = keys[i].bounds();
      inputs.push_back(c);
      ++stats.layer_tiles_processed;
    }
    RELIEF_CHECK(compositor_->composite(*gpu_, inputs, slots_.imagery().id(), slot, width, height));
    for (size_t i = 0; i < layers_.size(); ++i) {
      if (processed[i] && cpu_) cpu_->forget({i, keys[i], version_});
    }
    glFinish();  // what processing costs, apart from drawing
    const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
    stats.processing_seconds += seconds;
    processed_this_frame_ += seconds;
    made.layer = slot;
    return made;
  }

  // Layers processed on the CPU in an interactive frame: the view's own
  // composites are asked for first (jobs submitted where the layers' tiles
  // are resident; missing tiles are requested and never waited for), then,
  // when the workers' estimate fits what is left of the processing budget,
  // the frame waits for them (at most that long). Processing is not I/O: a
  // view whose processing fits is complete in this frame, not the next; one
  // that does not shows ancestors meanwhile, as before. The wait is not
  // charged to the budget of making composites: uploading results that are
  // ready costs little, and dropping them would waste the wait.
  Status process_view_on_cpu(const lod::Selection& selection, gl::Uploads& uploads,
                             FrameStats& stats) {
    const bool wanted = std::ranges::any_of(
        layers_, [&](const TextureLayer& l) { return on_cpu(l) && !l.tiles->blocking(); });
    if (!wanted) return {};
    const int finest = layers_[reference_].store->manifest().max_level;
    std::set<TileKey> asked;
    for (const lod::SelectedQuad& quad : selection.quads) {
      const int level = std::min(quad.key.level, finest), up = quad.key.level - level;
      const TileKey a{level, quad.key.x >> up, quad.key.y >> up};
      if (asked.insert(a).second) RELIEF_TRY(make_composite(a, quad.priority, uploads, stats));
    }
    const double left = processing_per_frame_ - processed_this_frame_;
    if (!cpu_ || !(cpu_->estimated_seconds() <= left)) return {};
    const auto start = Clock::now();
    cpu_->wait_idle(left);
    stats.processing_wait_seconds += std::chrono::duration<double>(Clock::now() - start).count();
    return {};
  }

  // Whether layer l's chain runs on the CPU (ProcessOn).
  bool on_cpu(const TextureLayer& l) const {
    if (l.chain.steps.empty() || !l.lenses.empty()) return false;
    return l.process_on == ProcessOn::cpu || (l.process_on == ProcessOn::automatic && software_);
  }

  // Layer i's tile `key` through its chain on the CPU: for stills now (every
  // core), for interactive frames by the workers (null until done).
  Result<lod::TilePtr> process_on_cpu(size_t i, const TileKey& key, const lod::TilePtr& tile,
                                      double priority) {
    const TextureLayer& l = layers_[i];
    const tiles::Manifest& man = l.store->manifest();
    CpuLayerProcessing::Job job;
    job.chain = gpuprocess::scale_chain(l.chain, std::ldexp(1.0, man.max_level - key.level));
    job.tile = tile;
    job.border = man.border;
    job.stats = {man.stats.min, man.stats.max, man.stats.mean, man.stats.stddev};
    job.priority = priority;
    // The layer alone makes the composite: the colour mapping runs on the
    // CPU too, and the frame only uploads the colours.
    if (layers_.size() == 1) job.colours = {{l.range_min, l.range_max, l.colormap, l.opacity}};
    if (l.tiles->blocking()) {
      ThreadExecutor executor;
      auto out = gpuprocess::run_chain_cpu(job.chain, *tile, job.border, &job.stats, executor);
      if (!out) return fail(out.error().message);
      if (const auto& c = job.colours) {
        *out = gpuprocess::map_colours_cpu(*out, c->range_min, c->range_max, c->map, c->opacity);
      }
      return std::make_shared<const tiles::Raster>(std::move(*out));
    }
    if (!cpu_) cpu_ = std::make_unique<CpuLayerProcessing>(0, on_processed_);
    return cpu_->get_or_submit({i, key, version_}, std::move(job));
  }

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

}  // namespace

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

Status check_texture_layer(const TextureLayer& l) {
  assert(l.store);
  const std::string name = l.store->root().string();
  RELIEF_CHECK(gpuprocess::check_chain_for(l.chain, l.store->manifest(), name));
  if (!(l.range_min < l.range_max)) {
    return fail(fmt::format("{}: the value range's minimum ({}) must be below its maximum ({})",
                            name, l.range_min, l.range_max));
  }
  if (!(l.opacity >= 0 && l.opacity <= 1)) {
    return fail(fmt::format("{}: opacity {} is not in [0, 1]", name, l.opacity));
  }
  for (const Lens& lens : l.lenses) {
    if (!(lens.radius_m > 0) || !std::isfinite(lens.radius_m)) {
      return fail(fmt::format("{}: a lens radius must be > 0 m, not {}", name, lens.radius_m));
    }
    if (!(std::abs(lens.lat) <= 90) || !(std::abs(lens.lon) <= 360)) {
      return fail(fmt::format("{}: lens centre {},{} is not a longitude, latitude", name, lens.lon,
                              lens.lat));
    }
    if (l.store->manifest().sample_type != tiles::SampleType::Float32) {
      return fail(fmt::format("{}: lenses are for single-band stores, not RGBA imagery", name));
    }
    RELIEF_CHECK(gpuprocess::check_chain_for(lens.chain, l.store->manifest(), name + " (lens)"));
  }
  return {};
}

Result<std::vector<float>> capture_positions(TerrainRenderer& renderer, const lod::View& view,
                                             const lod::Selection& selection,
                                             const RenderOptions& options,
                                             const lod::RefinedMesh* refined) {
  return static_cast<GlTerrainRenderer&>(renderer).capture(view, selection, options, refined);
}

}  // namespace relief::render
