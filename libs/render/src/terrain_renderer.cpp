#include "relief/render/terrain_renderer.h"

#include <chrono>
#include <cmath>
#include <unordered_map>

#include <fmt/format.h>

#include "gl.h"
#include "shaders.h"
#include "texture_cache.h"

namespace relief::render {
namespace {

using geo::TileKey;
using Clock = std::chrono::steady_clock;

struct Vertex {
  float rel[3];
  float up[3];
  float uv[2];
  uint32_t flags;
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

// A linear-filtered, edge-clamped 2-D texture holding `pixels`.
GLuint make_texture(GLenum internal_format, int w, int h, GLenum format, GLenum type,
                    const void* pixels) {
  GLuint t = 0;
  glCreateTextures(GL_TEXTURE_2D, 1, &t);
  glTextureStorage2D(t, 1, internal_format, w, h);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  glTextureSubImage2D(t, 0, 0, 0, w, h, format, type, pixels);
  glTextureParameteri(t, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  glTextureParameteri(t, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  glTextureParameteri(t, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTextureParameteri(t, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  return t;
}

class GlTerrainRenderer final : public TerrainRenderer {
 public:
  GlTerrainRenderer(lod::TerrainModel& elevation, const tiles::Store* imagery,
                    lod::TileProvider* imagery_tiles, uint64_t gpu_budget)
      : elevation_(elevation), imagery_(imagery), textures_(gpu_budget) {
    if (imagery_ && !imagery_tiles) {  // a still: read when needed
      owned_imagery_tiles_ = lod::blocking_provider(*imagery_, uint64_t{256} << 20);
      imagery_tiles = owned_imagery_tiles_.get();
    }
    imagery_tiles_ = imagery_tiles;
  }
  ~GlTerrainRenderer() override {
    glDeleteTextures(1, &zero_texture_);
    glDeleteBuffers(1, &vertex_buffer_);
    glDeleteBuffers(1, &index_buffer_);
    glDeleteVertexArrays(1, &vao_);
    glDeleteProgram(program_);
  }

  Status init() {
    program_ = RELIEF_TRY(link_program(kTerrainVertexShader, kTerrainFragmentShader));
    const lod::MeshTopology& mesh = elevation_.mesh();
    glCreateVertexArrays(1, &vao_);
    glCreateBuffers(1, &index_buffer_);
    glNamedBufferStorage(index_buffer_, mesh.indices().size() * sizeof(uint32_t),
                         mesh.indices().data(), 0);
    glVertexArrayElementBuffer(vao_, index_buffer_);
    glCreateBuffers(1, &vertex_buffer_);
    glVertexArrayVertexBuffer(vao_, 0, vertex_buffer_, 0, sizeof(Vertex));
    auto attribute = [&](GLuint index, GLint count, GLenum type, size_t offset) {
      glEnableVertexArrayAttrib(vao_, index);
      if (type == GL_UNSIGNED_INT) {
        glVertexArrayAttribIFormat(vao_, index, count, type, static_cast<GLuint>(offset));
      } else {
        glVertexArrayAttribFormat(vao_, index, count, type, GL_FALSE, static_cast<GLuint>(offset));
      }
      glVertexArrayAttribBinding(vao_, index, 0);
    };
    attribute(0, 3, GL_FLOAT, offsetof(Vertex, rel));
    attribute(1, 3, GL_FLOAT, offsetof(Vertex, up));
    attribute(2, 2, GL_FLOAT, offsetof(Vertex, uv));
    attribute(3, 1, GL_UNSIGNED_INT, offsetof(Vertex, flags));
    const float zero = 0;
    zero_texture_ = make_texture(GL_R32F, 1, 1, GL_RED, GL_FLOAT, &zero);
    if (auto e = gl_error(); !e.empty()) return fail("renderer setup: " + e);
    return {};
  }

  Result<FrameStats> draw(const lod::View& view, const lod::Selection& selection,
                          RenderTarget& target, const RenderOptions& o) override {
    const auto start = Clock::now();
    FrameStats stats;
    textures_.begin_frame();
    const uint64_t uploads_before = textures_.uploads(), evicted_before = textures_.evicted();
    const lod::MeshTopology& mesh = elevation_.mesh();
    const size_t per_quad = mesh.vertices().size();
    // Vertices go to the GPU in batches of whole quads, at most kBatchVertices
    // at a time, so a frame of any size fits in bounded memory.
    const size_t batch_quads = std::max<size_t>(1, kBatchVertices / per_quad);
    const size_t bytes = std::min(selection.quads.size(), batch_quads) * per_quad * sizeof(Vertex);
    if (bytes > vertex_capacity_) {
      glDeleteBuffers(1, &vertex_buffer_);
      glCreateBuffers(1, &vertex_buffer_);
      glNamedBufferStorage(vertex_buffer_, static_cast<GLsizeiptr>(bytes), nullptr,
                           GL_DYNAMIC_STORAGE_BIT);
      glVertexArrayVertexBuffer(vao_, 0, vertex_buffer_, 0, sizeof(Vertex));
      vertex_capacity_ = bytes;
    }
    // Textures of every quad before the first draw call (a complete frame).
    struct QuadTextures {
      GLuint own, parent, imagery;
      lod::DataWindow own_window, parent_window, imagery_window;
    };
    std::vector<QuadTextures> textures;
    for (const auto& q : selection.quads) {
      QuadTextures t;
      t.own_window = elevation_.window(q.key);
      t.parent_window = elevation_.parent_window(q.key);
      t.own = RELIEF_TRY(height_texture(t.own_window.tile));
      t.parent = RELIEF_TRY(height_texture(t.parent_window.tile));
      std::tie(t.imagery_window, t.imagery) = RELIEF_TRY(imagery_for(q));
      textures.push_back(t);
    }
    stats.prepare_seconds = std::chrono::duration<double>(Clock::now() - start).count();
    stats.gpu_textures = static_cast<uint32_t>(textures_.count());
    stats.gpu_bytes = textures_.used_bytes();
    stats.gpu_budget = textures_.budget_bytes();
    stats.uploads = static_cast<uint32_t>(textures_.uploads() - uploads_before);
    stats.gpu_evicted = static_cast<uint32_t>(textures_.evicted() - evicted_before);

    const auto gpu_start = Clock::now();
    target.bind();
    glClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_GREATER);
    glEnable(GL_CULL_FACE);
    glCullFace(GL_BACK);
    glFrontFace(GL_CCW);
    glClearColor(o.sky[0], o.sky[1], o.sky[2], 1);
    glClearDepth(0);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    glUseProgram(program_);
    glBindVertexArray(vao_);
    float vp[16];
    view_projection(view, vp);
    glUniformMatrix4fv(location("view_projection"), 1, GL_FALSE, vp);
    glUniform1i(location("own_heights"), 0);
    glUniform1i(location("parent_heights"), 1);
    glUniform1i(location("imagery"), 2);
    glUniform1i(location("border"), elevation_.border());
    glUniform1i(location("imagery_border"), imagery_ ? imagery_->manifest().border : 0);
    glUniform1f(location("exaggeration"), o.exaggeration);
    double fill_seconds = 0;
    for (size_t q = 0; q < selection.quads.size(); ++q) {
      if (q % batch_quads == 0) {
        const auto fill_start = Clock::now();
        upload_vertices(view, selection, q, std::min(selection.quads.size(), q + batch_quads));
        fill_seconds += std::chrono::duration<double>(Clock::now() - fill_start).count();
      }
      const lod::SelectedQuad& quad = selection.quads[q];
      const QuadTextures& t = textures[q];
      const geo::GeoBox b = quad.key.bounds();
      glBindTextureUnit(0, t.own);
      glBindTextureUnit(1, t.parent);
      glBindTextureUnit(2, t.imagery ? t.imagery : zero_texture_);
      auto window = [&](const char* name, const lod::DataWindow& w) {
        glUniform4f(location(name), static_cast<float>(w.x0), static_cast<float>(w.y0),
                    static_cast<float>(w.width), static_cast<float>(w.height));
      };
      window("own_window", t.own_window);
      window("parent_window", t.parent_window);
      window("imagery_window", t.imagery_window);
      glUniform1i(location("has_own"), t.own_window.tile ? 1 : 0);
      glUniform1i(location("has_parent"), t.parent_window.tile ? 1 : 0);
      glUniform1i(location("has_imagery"), t.imagery ? 1 : 0);
      glUniform1ui(location("coarse_sides"), quad.coarse_sides);
      glUniform1ui(location("coarse_corners"), quad.coarse_corners);
      glUniform2f(location("lat_range"), static_cast<float>(b.north), static_cast<float>(b.south));
      // North-south spacing of the data tile's samples (the quad's, or its ancestor's).
      const double quad_samples = t.own_window.height, spacing_deg = b.height() / quad_samples;
      glUniform1f(location("sample_metres"),
                  static_cast<float>(spacing_deg * 3.14159265358979323846 / 180 * 6371000.0));
      glDrawElementsBaseVertex(
          GL_TRIANGLES, static_cast<GLsizei>(mesh.index_count(quad.finer_sides)), GL_UNSIGNED_INT,
          reinterpret_cast<const void*>(static_cast<uintptr_t>(mesh.first_index(quad.finer_sides)) *
                                        sizeof(uint32_t)),
          static_cast<GLint>((q % batch_quads) * per_quad));
      ++stats.draw_calls;
      stats.triangles += mesh.triangle_count(quad.finer_sides);
    }
    glFinish();
    stats.gpu_seconds =
        std::chrono::duration<double>(Clock::now() - gpu_start).count() - fill_seconds;
    stats.prepare_seconds += fill_seconds;
    if (auto e = gl_error(); !e.empty()) return fail("drawing: " + e);
    return stats;
  }

 private:
  static constexpr size_t kBatchVertices = size_t{1} << 21;  // 64 MiB of vertices

  // Vertices of quads [first, last) relative to the eye: double until after
  // the subtraction, then float.
  void upload_vertices(const lod::View& view, const lod::Selection& selection, size_t first,
                       size_t last) {
    const lod::MeshTopology& mesh = elevation_.mesh();
    const size_t per_quad = mesh.vertices().size();
    staging_.resize(per_quad * (last - first));
    for (size_t q = first; q < last; ++q) {
      const geo::GeoBox b = selection.quads[q].key.bounds();
      for (size_t i = 0; i < per_quad; ++i) {
        const lod::MeshVertex& mv = mesh.vertices()[i];
        const double lon = b.west + mv.u * b.width(), lat = b.north - mv.v * b.height();
        const lod::Vec3 p = lod::ecef(lon, lat, 0) - view.eye, up = lod::up_at(lon, lat);
        Vertex& v = staging_[(q - first) * per_quad + i];
        v.rel[0] = static_cast<float>(p.x), v.rel[1] = static_cast<float>(p.y),
        v.rel[2] = static_cast<float>(p.z);
        v.up[0] = static_cast<float>(up.x), v.up[1] = static_cast<float>(up.y),
        v.up[2] = static_cast<float>(up.z);
        v.uv[0] = mv.u, v.uv[1] = mv.v;
        v.flags = static_cast<uint32_t>(mv.sides) | static_cast<uint32_t>(mv.corner) << 4;
      }
    }
    glNamedBufferSubData(vertex_buffer_, 0,
                         static_cast<GLsizeiptr>(staging_.size() * sizeof(Vertex)),
                         staging_.data());
  }

  GLint location(const char* name) {
    auto it = locations_.find(name);
    if (it == locations_.end())
      it = locations_.emplace(name, glGetUniformLocation(program_, name)).first;
    return it->second;
  }

  Result<GLuint> height_texture(const std::optional<TileKey>& key) {
    if (!key) return zero_texture_;
    if (auto t = textures_.find({*key, false})) return *t;
    const lod::TerrainModel::TilePtr tile = RELIEF_TRY(elevation_.tile(*key));
    if (!tile) return zero_texture_;
    const GLuint t =
        make_texture(GL_R32F, tile->width(), tile->height(), GL_RED, GL_FLOAT, tile->f32().data());
    textures_.insert({*key, false}, t, tile->byte_size());
    return t;
  }

  // The imagery of a quad: the texture of the imagery tile at the quad's
  // level (or the imagery's finest), else of its nearest ancestor whose
  // texture or decoded tile is at hand (non-blocking providers: the wanted
  // tile is requested meanwhile). Colour has no cracks to fear, so any
  // ancestor will do.
  Result<std::pair<lod::DataWindow, GLuint>> imagery_for(const lod::SelectedQuad& quad) {
    lod::DataWindow w;
    if (!imagery_) return std::pair{w, GLuint{0}};
    const TileKey& key = quad.key;
    const int finest = std::min(key.level, imagery_->manifest().max_level);
    GLuint texture = 0;
    int m = key.level - finest;
    for (TileKey a{finest, key.x >> m, key.y >> m};; a = *a.parent(), ++m) {
      if (imagery_->has_tile(a)) {
        if (auto t = textures_.find({a, true})) {
          texture = *t;
        } else if (const lod::TilePtr tile = RELIEF_TRY(imagery_tiles_->get(a))) {
          texture = make_texture(GL_RGBA8, tile->width(), tile->height(), GL_RGBA, GL_UNSIGNED_BYTE,
                                 tile->u8().data());  // premultiplied by decode_tile
          textures_.insert({a, true}, texture, tile->byte_size());
        } else if (a.level == finest) {
          imagery_tiles_->request(a, quad.priority);
        }
        if (texture) {
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
    return std::pair{w, texture};
  }

  lod::TerrainModel& elevation_;
  const tiles::Store* imagery_;
  std::unique_ptr<lod::TileProvider> owned_imagery_tiles_;
  lod::TileProvider* imagery_tiles_ = nullptr;
  GLuint program_ = 0, vao_ = 0, vertex_buffer_ = 0, index_buffer_ = 0, zero_texture_ = 0;
  size_t vertex_capacity_ = 0;
  std::vector<Vertex> staging_;
  std::unordered_map<std::string, GLint> locations_;
  TextureCache textures_;
};

}  // namespace

Result<std::unique_ptr<TerrainRenderer>> TerrainRenderer::create(lod::TerrainModel& elevation,
                                                                 const tiles::Store* imagery,
                                                                 uint64_t gpu_budget,
                                                                 lod::TileProvider* imagery_tiles) {
  if (imagery && imagery->manifest().sample_type != tiles::SampleType::UInt8) {
    return fail(imagery->root().string() + ": --imagery needs an imagery store (RGBA tiles)");
  }
  auto r = std::make_unique<GlTerrainRenderer>(elevation, imagery, imagery_tiles, gpu_budget);
  RELIEF_CHECK(r->init());
  return std::unique_ptr<TerrainRenderer>(std::move(r));
}

}  // namespace relief::render
