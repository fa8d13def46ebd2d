// Drawing a frame: the program, the buffers every frame shares and the GL
// state, then one indirect draw of what prepare() made (terrain_geometry.cpp),
// into a target or, for tests, captured by transform feedback.
#include <chrono>

#include <fmt/format.h>

#include "gl_terrain_renderer.h"
#include "shaders.h"

namespace relief::render {
namespace {

using Clock = std::chrono::steady_clock;

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

}  // namespace

// `draped`: imagery or texture layers will be drawn (the fragment shader's variant).
Status GlTerrainRenderer::init(bool draped) {
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
Status GlTerrainRenderer::warm_up() {
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

void GlTerrainRenderer::set_draw_state(const RenderOptions& o) {
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

Result<FrameStats> GlTerrainRenderer::draw(const lod::View& view, const lod::Selection& selection,
                                           RenderTarget& target, const RenderOptions& o,
                                           const lod::RefinedMesh* refined) {
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

Result<std::vector<float>> GlTerrainRenderer::capture(const lod::View& view,
                                                      const lod::Selection& selection,
                                                      const RenderOptions& o,
                                                      const lod::RefinedMesh* refined) {
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

// Binds everything prepare() made.
void GlTerrainRenderer::bind(gl::Program& program, const lod::View& view, const RenderOptions& o) {
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
uint32_t GlTerrainRenderer::multi_draw(const lod::Selection& selection) {
  if (selection.quads.empty()) return 0;
  glMultiDrawElementsIndirect(GL_TRIANGLES, GL_UNSIGNED_INT, nullptr,
                              static_cast<GLsizei>(selection.quads.size()), 0);
  return 1;
}

}  // namespace relief::render
