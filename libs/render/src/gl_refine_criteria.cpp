#include "relief/render/gl_refine_criteria.h"

#include <algorithm>
#include <list>
#include <map>

#include <fmt/format.h>

#include "gl_backend.h"
#include "refine_criteria_shader.h"
#include "relief/geo/ellipsoid.h"

namespace relief::render {

namespace {

// Diamond errors kept on the GPU between frames, by their owner (one per
// data tile), under a byte budget: a view that does not change uploads none
// again. Keyed by the owner's control block (owner_less), not its address:
// an entry keeps its weak reference, so errors made later for another tile
// never match it, even at the same address. Entries whose owner expired go
// at the end of the next frame.
class ResidentErrors {
 public:
  explicit ResidentErrors(uint64_t budget) : budget_(budget) {}

  // The buffer holding q's errors, uploaded if it is not there yet.
  GLuint buffer(const lod::CriterionQuad& q, gl::Uploads& uploads) {
    auto it = entries_.find(q.errors_owner);
    if (it == entries_.end()) {
      Entry e;
      e.buffer = gl::Buffer::make_static(q.errors.data(), q.errors.size(), uploads);
      bytes_ += q.errors.size();
      it = entries_.emplace(std::weak_ptr<const void>(q.errors_owner), std::move(e)).first;
      lru_.push_front(it);
      it->second.at = lru_.begin();
    } else {
      lru_.splice(lru_.begin(), lru_, it->second.at);
    }
    it->second.frame = frame_;
    return it->second.buffer.id();
  }

  // After a frame: the expired go, then the least recently used over the
  // budget, except the frame's own.
  void end_frame() {
    for (auto it = entries_.begin(); it != entries_.end();) {
      it = it->first.expired() ? drop(it) : std::next(it);
    }
    while (bytes_ > budget_ && !lru_.empty() && lru_.back()->second.frame != frame_) {
      drop(lru_.back());
    }
    ++frame_;
  }
  uint64_t bytes() const { return bytes_; }

 private:
  struct Entry;
  using Entries = std::map<std::weak_ptr<const void>, Entry, std::owner_less<>>;
  struct Entry {
    gl::Buffer buffer;
    std::list<Entries::iterator>::iterator at;
    uint64_t frame = 0;
  };
  Entries::iterator drop(Entries::iterator it) {
    bytes_ -= it->second.buffer.size();
    lru_.erase(it->second.at);
    return entries_.erase(it);
  }
  uint64_t budget_, bytes_ = 0, frame_ = 0;
  Entries entries_;
  std::list<Entries::iterator> lru_;  // most recent first
};

}  // namespace

struct GlRefineCriteria::Impl {
  explicit Impl(uint64_t budget) : resident(budget) {}
  gl::Program program;
  ResidentErrors resident;
  gl::Buffer grid, sides, classes, class_offsets;
  gl::Uploads uploads;
  uint64_t read = 0;
  std::vector<double> grid_values;
  std::vector<float> side_values;

  void set(const char* name, double v) {
    glProgramUniform1d(program.id(), program.location(name), v);
  }
  void set(const char* name, int v) { glProgramUniform1i(program.id(), program.location(name), v); }
  void set(const char* name, const lod::Vec3& v) {
    glProgramUniform3d(program.id(), program.location(name), v.x, v.y, v.z);
  }

  void set_frame(const lod::CriterionFrame& f) {
    const lod::View& v = *f.view;
    set("eye", v.eye);
    set("view_right", v.right);
    set("view_up", v.up);
    set("view_forward", v.forward);
    set("pixels_per_radian", v.pixels_per_radian);
    set("corner", v.tan_half_x * v.tan_half_x + v.tan_half_y * v.tan_half_y);
    set("threshold", f.pixel_error);
    set("band", f.band);
    set("arc", f.arc);
    set("rounding", f.rounding);
    set("e2", geo::wgs84::kFirstEccentricitySquared);
    set("n", 1 << f.k);
    set("class_count", static_cast<int>(f.class_offsets.size()) - 1);
    const std::vector<GLint> offsets(f.class_offsets.begin(), f.class_offsets.end());
    class_offsets.write(offsets.data(), offsets.size() * sizeof(GLint), uploads);
    set("slot_count", static_cast<int>(f.class_offsets.back()));
  }

  // One quad: its inputs uploaded, its classes computed and read back.
  void evaluate(const lod::CriterionQuad& q, uint32_t slots, std::vector<uint8_t>& out) {
    set("west_sin", q.west_sin);
    set("west_cos", q.west_cos);
    set("north_sin", q.north_sin);
    set("north_cos", q.north_cos);
    set("cell", q.cell);
    set("level_error", q.level_error);
    set("has_errors", q.errors.empty() ? 0 : 1);
    const GLuint errors = q.errors.empty() ? 0 : resident.buffer(q, uploads);
    grid_values.assign(q.steps.begin(), q.steps.end());
    set("spreads_at", static_cast<int>(grid_values.size()));
    grid_values.insert(grid_values.end(), q.spreads.begin(), q.spreads.end());
    set("normals_at", static_cast<int>(grid_values.size()));
    grid_values.insert(grid_values.end(), q.normals.begin(), q.normals.end());
    grid.write(grid_values.data(), grid_values.size() * sizeof(double), uploads);
    side_values.clear();
    GLint first[4], count[4];
    for (size_t s = 0; s < 4; ++s) {
      first[s] = static_cast<GLint>(side_values.size());
      count[s] = static_cast<GLint>(q.sides[s].size());
      side_values.insert(side_values.end(), q.sides[s].begin(), q.sides[s].end());
    }
    if (side_values.empty()) side_values.push_back(0);  // a buffer must be bound
    sides.write(side_values.data(), side_values.size() * sizeof(float), uploads);
    glProgramUniform1iv(program.id(), program.location("side_first"), 4, first);
    glProgramUniform1iv(program.id(), program.location("side_count"), 4, count);
    const uint32_t words = (slots + 3) / 4;
    if (classes.size() < words * 4u) {  // sized once: every word is written
      const std::vector<uint8_t> zero(words * 4u);
      classes.write(zero.data(), zero.size(), uploads);
    }
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, errors ? errors : grid.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, grid.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, sides.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 3, classes.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 4, class_offsets.id());
    glUseProgram(program.id());
    // At most 65 535 groups along x (the least GL guarantees): rows of them.
    const GLuint groups = (words + 63) / 64, row = std::min<GLuint>(groups, 65535);
    glDispatchCompute(row, (groups + row - 1) / row, 1);
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    out.resize(words * 4u);
    glGetNamedBufferSubData(classes.id(), 0, static_cast<GLsizeiptr>(words) * 4, out.data());
    read += words * 4u;
  }
};

GlRefineCriteria::GlRefineCriteria(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
GlRefineCriteria::~GlRefineCriteria() = default;

Result<std::unique_ptr<GlRefineCriteria>> GlRefineCriteria::create(uint64_t budget_bytes) {
  auto impl = std::make_unique<Impl>(budget_bytes);
  auto program = gl::Program::link_compute(kRefineCriteriaShader);
  if (!program) return fail("the refinement's criterion shader: " + program.error().message);
  impl->program = std::move(*program);
  return std::unique_ptr<GlRefineCriteria>(new GlRefineCriteria(std::move(impl)));
}

Status GlRefineCriteria::evaluate(const lod::CriterionFrame& frame,
                                  std::span<const lod::CriterionQuad> quads,
                                  std::vector<std::vector<uint8_t>>& classes) {
  const size_t class_count = frame.class_offsets.empty() ? 0 : frame.class_offsets.size() - 1;
  if (class_count < 1 || class_count > 64) {
    return fail(fmt::format("GL refinement criteria: {} classes of diamonds (1 to 64 supported)",
                            class_count));
  }
  for (const lod::CriterionQuad& q : quads) {
    if (!q.errors.empty() && !q.errors_owner) {
      return fail("GL refinement criteria: a quad's diamond errors have no owner");
    }
  }
  while (glGetError() != GL_NO_ERROR) {
  }  // errors left by others are not this evaluation's
  const uint32_t slots = frame.class_offsets.back();
  classes.resize(quads.size());
  impl_->set_frame(frame);
  for (size_t i = 0; i < quads.size(); ++i) impl_->evaluate(quads[i], slots, classes[i]);
  impl_->resident.end_frame();
  glUseProgram(0);
  if (const GLenum e = glGetError(); e != GL_NO_ERROR) {
    return fail(fmt::format("GL refinement criteria: GL error 0x{:x}", e));
  }
  return {};
}

uint64_t GlRefineCriteria::bytes_uploaded() const {
  return impl_->uploads.geometry;
}
uint64_t GlRefineCriteria::bytes_read() const {
  return impl_->read;
}
uint64_t GlRefineCriteria::resident_bytes() const {
  return impl_->resident.bytes();
}

}  // namespace relief::render
