#include "relief/parallel/frame_renderer.h"

#include <cassert>
#include <cmath>

#include "relief/lod/terrain_model.h"

namespace relief::parallel {

namespace {

// As view::Scene: the brute-force reference has one vertex per finest sample.
int mesh_level(const tiles::Store& s, const view::SceneOptions& o) {
  return o.full_resolution ? static_cast<int>(std::log2(s.grid().height())) : o.mesh_level;
}

}  // namespace

FrameRenderer::FrameRenderer(const tiles::Store& elevation, const view::SceneOptions& options)
    : options_(options), mesh_(mesh_level(elevation, options)) {
  if (edge_marks()) {
    options_.selection.neighbour_indices = true;  // refinement walks across quads
    refine_cache_ = std::make_unique<lod::RefineCache>(options_.loader.memory_budget);
  }
}

FrameRenderer::~FrameRenderer() = default;

bool FrameRenderer::edge_marks() const {
  return options_.selection.mode == lod::LodMode::edge_marks && !options_.full_resolution;
}

Result<std::unique_ptr<FrameRenderer>> FrameRenderer::create(const tiles::Store& elevation,
                                                             const tiles::Store* imagery,
                                                             const view::SceneOptions& options) {
  std::unique_ptr<FrameRenderer> r(new FrameRenderer(elevation, options));
  r->terrain_ =
      std::make_unique<lod::TerrainModel>(&elevation, r->mesh_, options.loader.memory_budget);
  r->renderer_ =
      RELIEF_TRY(render::TerrainRenderer::create(*r->terrain_, imagery, options.gpu_budget));
  return r;
}

Status FrameRenderer::select(const lod::View& view) {
  terrain_->begin_frame();
  selection_ = RELIEF_TRY(lod::select_quads(view, *terrain_, options_.selection));
  terrain_->end_frame();
  refined_.reset();
  if (edge_marks()) {
    lod::RefineOptions ro;
    ro.pixel_error = options_.selection.pixel_error;
    ro.variant = options_.refine_variant;
    ro.cache = refine_cache_.get();
    refined_ = RELIEF_TRY(lod::refine(view, *terrain_, selection_, ro));
  }
  return {};
}

std::vector<uint64_t> FrameRenderer::quad_triangles() const {
  std::vector<uint64_t> out;
  out.reserve(selection_.quads.size());
  for (size_t i = 0; i < selection_.quads.size(); ++i) {
    out.push_back(refined_ ? refined_->quads[i].index_count / 3
                           : mesh_.index_count(selection_.quads[i].finer_sides) / 3);
  }
  return out;
}

Result<std::vector<TriangleRange>> FrameRenderer::quads_in_window(const lod::View& view) {
  const std::vector<uint64_t> triangles = quad_triangles();
  std::vector<TriangleRange> keep(triangles.size());
  for (size_t i = 0; i < keep.size(); ++i) keep[i] = {0, triangles[i]};
  // Boxes bound the unexaggerated surface only.
  if (view.window.empty() || options_.render.exaggeration != 1.0f) return keep;
  const std::array<lod::Plane, 5> planes = lod::window_planes(view);
  for (size_t i = 0; i < keep.size(); ++i) {
    const lod::TerrainModel::QuadInfo* info = RELIEF_TRY(terrain_->quad(selection_.quads[i].key));
    // A margin for the meshes' float arithmetic and borders taken from coarser data.
    const lod::Vec3 lo = info->box.lo, hi = info->box.hi;
    const double pad = 0.01 * length(hi - lo) + 10;
    const lod::Vec3 p{pad, pad, pad};
    if (lod::outside(planes, lo - p, hi + p)) keep[i] = {};
  }
  return keep;
}

Result<render::FrameStats> FrameRenderer::draw(const lod::View& view,
                                               std::span<const TriangleRange> parts,
                                               render::RenderTarget& target) {
  lod::Selection part;
  part.stats = selection_.stats;
  std::optional<lod::RefinedMesh> refined_part;
  if (refined_) {
    refined_part.emplace();
    refined_part->grid_k = refined_->grid_k;
    refined_part->indices = refined_->indices;  // quads index into the whole mesh's indices
    refined_part->stats = refined_->stats;
  }
  for (size_t i = 0; i < selection_.quads.size(); ++i) {
    const TriangleRange& range = parts[i];
    if (range.count == 0) continue;
    part.quads.push_back(selection_.quads[i]);
    if (refined_) {
      lod::RefinedQuad q = refined_->quads[i];
      assert(3 * (range.first + range.count) <= q.index_count);
      q.first_index += static_cast<uint32_t>(3 * range.first);
      q.index_count = static_cast<uint32_t>(3 * range.count);
      refined_part->quads.push_back(q);
    } else {
      // A fixed mesh is drawn whole (splits_quads() is false).
      assert(range.first == 0 &&
             range.count == mesh_.index_count(selection_.quads[i].finer_sides) / 3);
    }
  }
  part.stats.quads = static_cast<uint32_t>(part.quads.size());
  return renderer_->draw(view, part, target, options_.render,
                         refined_part ? &*refined_part : nullptr);
}

}  // namespace relief::parallel
