// What a frame draws, made ready on the GPU (prepare()): per quad a record of
// its windows and texture layers (terrain_textures.cpp, terrain_composites.cpp)
// and a draw command, and a refined mesh's indices and vertex grid; each
// buffer uploaded only when it differs from the last frame's.
#include <algorithm>
#include <numeric>

#include <fmt/format.h>

#include "gl_terrain_renderer.h"

namespace relief::render {
namespace {

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

}  // namespace

// Records, draw commands and textures of a frame, on the GPU; uploads only
// what differs from the previous frame. Draw commands nearest quad first
// when `near_to_far`, else in the selection's order (captures).
Result<FrameStats> GlTerrainRenderer::prepare(const lod::View& view,
                                              const lod::Selection& selection,
                                              const lod::RefinedMesh* refined, bool near_to_far) {
  if (selection.quads.size() > max_quads_) {
    return fail(fmt::format("{} quads in a frame, more than the {} the GPU's buffer textures hold",
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
void GlTerrainRenderer::sort_near_to_far() {
  order_.resize(commands_.size());
  std::iota(order_.begin(), order_.end(), 0u);
  std::stable_sort(order_.begin(), order_.end(),
                   [&](uint32_t a, uint32_t b) { return nearness_[a] < nearness_[b]; });
  sorted_commands_.clear();
  for (uint32_t i : order_) sorted_commands_.push_back(commands_[i]);
  commands_.swap(sorted_commands_);
}

// A refined mesh the GPU can draw without reading outside its buffers.
Status GlTerrainRenderer::check_refined(const lod::RefinedMesh& r,
                                        const lod::Selection& selection) {
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
  if (!same &&
      std::any_of(r.indices.begin(), r.indices.end(), [&](uint32_t i) { return i >= vertices; })) {
    return fail(
        fmt::format("refined mesh: a vertex id past the {} of grid level {}", vertices, r.grid_k));
  }
  return {};
}

}  // namespace relief::render
