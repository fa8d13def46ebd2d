// The triangles of the marks (refined_mesh.h): one refiner's, the lanes'
// gathered, or the last frame's reused.
#include <algorithm>
#include <cstdlib>
#include <utility>

#include "refiner.h"

namespace relief::lod::refinement {

// `expected`: about as many indices as the last frame's (growing the
// buffer took a few percent of a frame in copies and page faults).
RefinedMesh Refiner::mesh(size_t expected) {
  RefinedMesh out;
  out.indices.reserve(expected + expected / 8);
  out.grid_k = grid_.k();
  out.quads.resize(quads_.size());
  for (size_t i = 0; i < quads_.size(); ++i) {
    out.quads[i].first_index = static_cast<uint32_t>(out.indices.size());
    emit_quad(static_cast<int>(i), out.indices);
    out.quads[i].index_count = static_cast<uint32_t>(out.indices.size()) - out.quads[i].first_index;
  }
  out.stats = stats_;
  return out;
}

// The triangles of quad q's marks.
void Refiner::emit_quad(int q, std::vector<uint32_t>& out) {
  const int32_t n = grid_.n();
  for (int32_t h = 0; h < 2; ++h) {
    const GridPoint c{h * n + n / 2, n / 2};
    const GridPoint nw{h * n, 0}, ne{h * n + n, 0}, se{h * n + n, n}, sw{h * n, n};
    const std::pair<GridPoint, GridPoint> sides[] = {{nw, ne}, {ne, se}, {se, sw}, {sw, nw}};
    for (const auto& [a, b] : sides) emit(q, c, a, b, out);
  }
}

// The triangle with right angle at r and hypotenuse (a, b), or its children.
void Refiner::emit(int q, GridPoint r, GridPoint a, GridPoint b, std::vector<uint32_t>& out) {
  const GridPoint m{(a.x + b.x) / 2, (a.y + b.y) / 2};
  // A hypotenuse of two cells along an axis is a sample's side: never split.
  const bool sample_side = std::abs(a.x - b.x) + std::abs(a.y - b.y) == 2;
  if (!sample_side && mark_of(q, m) == kSplit) {
    emit(q, m, a, r, out);
    emit(q, m, r, b, out);
    return;
  }
  // Counter-clockwise seen from above: in (x, -y), as MeshTopology.
  const int64_t area = int64_t{a.x - r.x} * (r.y - b.y) - int64_t{r.y - a.y} * (b.x - r.x);
  if (area < 0) std::swap(a, b);
  const auto id = [this](GridPoint g) {
    return vertex_ids_(static_cast<uint32_t>(g.x), static_cast<uint32_t>(g.y));
  };
  // One at a time: inserted from a list, the ids went through the stack as
  // 32-bit stores read back in a 64-bit load (a stalled store forwarding).
  const uint32_t ir = id(r), ia = id(a), ib = id(b);
  out.push_back(ir);
  out.push_back(ia);
  out.push_back(ib);
}

// Lanes: the triangles of this lane's quads into `out`, each quad's
// (RefinedQuad relative to `out`) in `quads`.
void Refiner::emit_lane(std::vector<uint32_t>& out, std::vector<RefinedQuad>& quads) {
  out.clear();
  for (size_t i = 0; i < quads_.size(); ++i) {
    if (!mine(static_cast<int>(i))) continue;
    quads[i].first_index = static_cast<uint32_t>(out.size());
    emit_quad(static_cast<int>(i), out);
    quads[i].index_count = static_cast<uint32_t>(out.size()) - quads[i].first_index;
  }
}

// Lanes: the mesh of the triangles emit_lane() made, in quad order.
RefinedMesh Refiner::gather(const Lanes& lanes, const std::vector<std::vector<uint32_t>>& indices,
                            const std::vector<RefinedQuad>& at) const {
  RefinedMesh out;
  size_t total = 0;
  for (const RefinedQuad& q : at) total += q.index_count;
  out.indices.resize(total);
  out.grid_k = grid_.k();
  out.quads.resize(quads_.size());
  uint32_t next = 0;
  for (size_t i = 0; i < quads_.size(); ++i) {
    const std::vector<uint32_t>& from = indices[lanes.owner[i]];
    std::copy_n(from.begin() + at[i].first_index, at[i].index_count, out.indices.begin() + next);
    out.quads[i] = {next, at[i].index_count};
    next += at[i].index_count;
  }
  out.stats = stats_;
  return out;
}

RefinedMesh Refiner::reused_mesh() const {
  RefinedMesh out;
  out.grid_k = grid_.k();
  out.indices = history_->indices;
  out.quads = history_->quads;
  out.stats = stats_;
  out.stats.unresolved = history_->unresolved;
  out.stats.max_unresolved_pixels = history_->max_unresolved_pixels;
  out.stats.split_wanted = history_->split_wanted;
  return out;
}

}  // namespace relief::lod::refinement
