#include "relief/view/scene.h"

#include <algorithm>
#include <cassert>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <functional>
#include <mutex>
#include <optional>

#include <fmt/format.h>

#include "relief/base/memory_use.h"
#include "relief/lod/split_feedback.h"
#include "relief/render/gl_refine_criteria.h"
#include "relief/render/overlay.h"
#include "relief/render/render_target.h"
#include "relief/stream/radius_pager.h"
#include "relief/view/ground.h"
#include "relief/view/memory_budget.h"

namespace relief::view {

namespace {

// Where the camera will be `frames` frames from now at its present motion.
lod::Camera extrapolate(const lod::Camera& prev, const lod::Camera& now, double frames) {
  auto step = [&](double a, double b, bool angle) {
    const double d = angle ? std::remainder(b - a, 360.0) : b - a;
    return b + d * frames;
  };
  lod::Camera c = now;
  c.lon = std::remainder(step(prev.lon, now.lon, true), 360.0);
  c.lat = std::clamp(step(prev.lat, now.lat, false), -89.9, 89.9);
  c.height = std::max(now.height * 0.5, step(prev.height, now.height, false));
  c.heading = std::remainder(step(prev.heading, now.heading, true), 360.0);
  c.pitch = std::clamp(step(prev.pitch, now.pitch, false), -90.0, 90.0);
  return c;
}

// Asynchronous work that ended (SceneOptions::on_change): counted for
// wait_for_change(), then passed on. Shared with the threads that announce it.
struct Changes {
  std::function<void()> listener;
  std::mutex mutex;
  std::condition_variable changed;
  uint64_t count = 0;

  void announce() {
    {
      std::lock_guard lock(mutex);
      ++count;
    }
    changed.notify_all();
    if (listener) listener();
  }
};

bool moved(const lod::Camera& a, const lod::Camera& b) {
  return a.lon != b.lon || a.lat != b.lat || a.height != b.height || a.heading != b.heading ||
         a.pitch != b.pitch;
}

}  // namespace

struct Scene::Impl {
  const tiles::Store* store;  // null: the bare ellipsoid
  const tiles::Store* imagery;
  SceneOptions options;
  const Clock& clock;
  lod::MeshTopology mesh;
  std::shared_ptr<Changes> changes = std::make_shared<Changes>();
  std::unique_ptr<stream::TileLoader> loader, imagery_loader;
  std::vector<std::unique_ptr<stream::TileLoader>> layer_loaders;  // interactive texture layers
  std::unique_ptr<lod::TerrainModel> terrain;
  std::unique_ptr<render::TerrainRenderer> renderer;
  std::unique_ptr<lod::RefineCache> refine_cache;          // edge-mark frames
  std::unique_ptr<PooledExecutor> refine_threads;          // SceneOptions::refine_threads > 1
  std::unique_ptr<render::GlRefineCriteria> gpu_criteria;  // SceneOptions::refine_on_gpu
  lod::SplitFeedback split_feedback;                       // what the last refinements wanted split
  std::optional<lod::Camera> previous;                     // of the last frame, unless cut
  lod::Selection last;
  std::optional<lod::RefinedMesh> last_refined;
  // Edge-mark frames: the last frames' decisions, reused where the camera
  // moved too little to change them (the same mesh, at a fraction of the cost).
  lod::RefineHistory refine_history;
  uint64_t imagery_misses = 0;                 // a frame that missed imagery is not complete
  bool gpu_in_memory = false;                  // L3 is main memory (software rasteriser)
  std::optional<lod::Camera> prefetch_camera;  // set_prefetch_camera()
  bool frozen = false;                         // set_selection_frozen()
  // SceneOptions::uploads_per_frame: the tiles not on the GPU this frame's
  // selection admitted (uploaded before it draws).
  std::vector<geo::TileKey> admitted;
  bool drawn = false;  // a frame was drawn: `last` is its selection
  // SceneOptions::detect: the SAR layer's store, its hints and their overlay.
  const tiles::Store* hint_store = nullptr;
  std::unique_ptr<TargetHints> hints;
  std::unique_ptr<render::Overlay> overlay;
  std::vector<TargetHint> last_hints;

  Impl(const tiles::Store* s, const tiles::Store* i, const SceneOptions& o, const Clock& c)
      : store(s), imagery(i), options(o), clock(c), mesh(mesh_level(s, o)) {
    if (edge_marks()) {
      options.selection.neighbour_indices = true;  // refinement walks across quads
      refine_cache = std::make_unique<lod::RefineCache>(options.diamond_error_budget
                                                            ? options.diamond_error_budget
                                                            : options.loader.memory_budget);
      auto pool = std::make_unique<PooledExecutor>(options.refine_threads);
      if (pool->concurrency() > 1) refine_threads = std::move(pool);
    }
  }

  // What SceneOptions::memory_budget bounds, as it stands: the loaders'
  // resident tiles, the diamond errors, and L3 where it is main memory.
  uint64_t cached_bytes(const render::FrameStats& draw) const {
    uint64_t bytes = refine_cache ? refine_cache->bytes() : 0;
    if (loader) bytes += loader->resident_bytes();
    if (imagery_loader) bytes += imagery_loader->resident_bytes();
    for (const auto& l : layer_loaders) bytes += l->resident_bytes();
    if (gpu_in_memory) bytes += draw.gpu_allocated_bytes;
    return bytes;
  }

  bool edge_marks() const {
    return options.selection.mode == lod::LodMode::edge_marks && !options.full_resolution;
  }

  bool feeds_back() const { return edge_marks() && loader && options.split_feedback; }

  // The brute-force reference has one vertex per finest sample.
  static int mesh_level(const tiles::Store* s, const SceneOptions& o) {
    return o.full_resolution && s ? static_cast<int>(std::log2(s->grid().height())) : o.mesh_level;
  }

  // SceneOptions::uploads_per_frame as SelectionOptions::drawable_now: a
  // tile on the GPU, or one of the first tiles this frame admits.
  std::function<bool(const geo::TileKey&)> upload_budget() {
    return [this](const geo::TileKey& tile) {
      if (renderer->has_elevation_texture(tile)) return true;
      if (std::find(admitted.begin(), admitted.end(), tile) != admitted.end()) return true;
      if (admitted.size() >= options.uploads_per_frame) return false;
      admitted.push_back(tile);
      return true;
    };
  }

  // Draws `selection` with the texture and imagery loaders taking the
  // renderer's requests.
  Result<render::FrameStats> draw_selection(const lod::View& view, const lod::Selection& selection,
                                            render::RenderTarget& target,
                                            const lod::RefinedMesh* refined) {
    if (imagery_loader) imagery_loader->begin_frame();
    for (auto& l : layer_loaders) l->begin_frame();
    auto frame = renderer->draw(view, selection, target, options.render, refined);
    if (imagery_loader) imagery_loader->end_frame();
    for (auto& l : layer_loaders) l->end_frame();
    return frame;
  }

  // The hints of the hint store's tiles under `selection` (each quad's tile,
  // or its ancestor at the store's finest level), drawn over the frame.
  Status draw_hints(const lod::View& view, const lod::Selection& selection,
                    render::RenderTarget& target, FrameReport& report, Scene& scene) {
    const tiles::Manifest& m = hint_store->manifest();
    std::vector<geo::TileKey> keys;
    for (const lod::SelectedQuad& q : selection.quads) {
      if (q.key.level < m.min_level) continue;
      const int shift = std::max(0, q.key.level - m.max_level);
      keys.push_back({q.key.level - shift, q.key.x >> shift, q.key.y >> shift});
    }
    std::sort(keys.begin(), keys.end());
    keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
    HintSet set = RELIEF_TRY(hints->hints(keys, !loader && layer_loaders.empty()));
    report.hints = set.hints.size();
    report.hint_tiles_pending = set.missing;
    Ground ground;
    if (store) ground = resident_ground(scene);
    const auto height = [&](double lon, double lat) {
      return ground ? ground(lon, lat).value_or(0.0) : 0.0;
    };
    const std::vector<render::OverlayLine> lines = hint_glyphs(view, set.hints, {}, height);
    last_hints = std::move(set.hints);
    return overlay->draw(lines, target);
  }

  Status prefetch_along_motion(const lod::Camera& camera) {
    if (loader && prefetch_camera) {  // the known path's coming frame
      auto ahead = lod::make_view(*prefetch_camera);
      if (!ahead) return {};
      loader->set_prefetch(true);
      auto predicted = lod::select_quads(*ahead, *terrain, options.selection);
      loader->set_prefetch(false);
      if (!predicted) return std::unexpected(predicted.error());
      return {};
    }
    if (!loader || !options.prefetch || !previous) return {};
    const bool jumped =
        std::abs(camera.lon - previous->lon) + std::abs(camera.lat - previous->lat) > 1;
    if (jumped || !moved(*previous, camera)) return {};
    auto ahead = lod::make_view(extrapolate(*previous, camera, options.lookahead_frames));
    if (!ahead) return {};  // extrapolated into the ground or past a pole: nothing to prefetch
    loader->set_prefetch(true);
    auto predicted = lod::select_quads(*ahead, *terrain, options.selection);
    loader->set_prefetch(false);
    if (!predicted) return std::unexpected(predicted.error());
    return {};
  }
};

Scene::Scene(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Scene::~Scene() = default;

Result<std::unique_ptr<Scene>> Scene::create(const tiles::Store& elevation,
                                             const tiles::Store* imagery,
                                             const SceneOptions& options, const Clock& clock) {
  return create(&elevation, imagery, options, clock);
}

Result<std::unique_ptr<Scene>> Scene::create(const tiles::Store* elevation,
                                             const tiles::Store* imagery,
                                             const SceneOptions& options, const Clock& clock) {
  if (!options.texture_layers.empty() && imagery) {
    return fail("an imagery store and texture layers: give the imagery as an RGBA layer");
  }
  for (const render::TextureLayer& l : options.texture_layers) {
    RELIEF_CHECK(render::check_texture_layer(l));
  }
  SceneOptions o = options;
  if (!elevation) {
    // No heights to refine (edge marks need a store), and quads go down to
    // the draped texture's finest level.
    o.selection.mode = lod::LodMode::quads;
    if (o.selection.texture && o.selection.max_level < 0) {
      o.selection.max_level = o.selection.texture->manifest().max_level;
    }
  }
  bool gpu_in_memory = false;
  if (o.memory_budget) {
    CacheUse use;
    use.diamond_errors =
        elevation && o.selection.mode == lod::LodMode::edge_marks && !o.full_resolution;
    use.textures = imagery ? 1 : static_cast<int>(o.texture_layers.size());
    use.composites = !o.texture_layers.empty();
    use.gpu_in_memory = render::software_rasteriser();
    gpu_in_memory = use.gpu_in_memory;
    if (o.gpu_budget_given) use.gpu_given = o.gpu_budget;
    const CacheBudgets b = RELIEF_TRY(split_memory_budget(o.memory_budget, use));
    o.loader.memory_budget = b.elevation;
    o.diamond_error_budget = b.diamond_errors;
    if (use.textures) o.imagery_budget = b.texture_each;
    if (b.gpu) o.gpu_budget = *b.gpu;
  }
  auto impl = std::make_unique<Impl>(elevation, imagery, o, clock);
  impl->gpu_in_memory = gpu_in_memory;
  std::vector<render::TextureLayer> layers = options.texture_layers;
  if (options.interactive) {
    stream::LoaderOptions lo = o.loader;
    lo.clock = &clock;
    impl->changes->listener = options.on_change;
    lo.on_settled = [own = o.loader.on_settled, changes = impl->changes] {
      if (own) own();
      changes->announce();
    };
    if (elevation) {
      impl->loader = RELIEF_TRY(stream::TileLoader::create(*elevation, lo));
      impl->terrain = std::make_unique<lod::TerrainModel>(*elevation, impl->mesh, *impl->loader);
      // Diamond errors on the loader's threads, not in the frame that first draws a tile;
      // no exact quad errors there (only the quad mode's selection asks for them).
      if (impl->refine_cache) {
        impl->terrain->skip_exact_errors_on_load();
        impl->refine_cache->prepare_on_load(*impl->terrain);
      }
    } else {
      impl->terrain = std::make_unique<lod::TerrainModel>(nullptr, impl->mesh, 0);
    }
    lo.memory_budget = o.imagery_budget;
    if (imagery) impl->imagery_loader = RELIEF_TRY(stream::TileLoader::create(*imagery, lo));
    for (render::TextureLayer& l : layers) {
      impl->layer_loaders.push_back(RELIEF_TRY(stream::TileLoader::create(*l.store, lo)));
      l.tiles = impl->layer_loaders.back().get();
    }
  } else {
    impl->terrain =
        std::make_unique<lod::TerrainModel>(elevation, impl->mesh, o.loader.memory_budget);
    for (render::TextureLayer& l : layers) l.tiles = nullptr;  // read when needed
  }
  if (layers.empty()) {
    impl->renderer = RELIEF_TRY(render::TerrainRenderer::create(
        *impl->terrain, imagery, o.gpu_budget, impl->imagery_loader.get()));
  } else {
    impl->renderer = RELIEF_TRY(
        render::TerrainRenderer::create(*impl->terrain, std::move(layers), o.gpu_budget));
  }
  const auto announce = [changes = impl->changes] { changes->announce(); };
  if (options.interactive) impl->renderer->set_on_processed(announce);
  if (options.on_growth_ahead) impl->renderer->set_on_growth_ahead(options.on_growth_ahead);
  if (options.detect) {
    for (const render::TextureLayer& l : options.texture_layers) {
      if (l.store->manifest().kind == tiles::DatasetKind::Sar) {
        impl->hint_store = l.store;
        break;
      }
    }
    if (!impl->hint_store) return fail("--detect: needs a SAR texture layer (--texture SAR_STORE)");
    impl->hints = RELIEF_TRY(
        TargetHints::create(*impl->hint_store, options.detector,
                            options.interactive ? std::function<void()>(announce) : nullptr));
    impl->overlay = RELIEF_TRY(render::Overlay::create());
  }
  return std::unique_ptr<Scene>(new Scene(std::move(impl)));
}

Status Scene::set_texture_layers(std::vector<render::TextureLayer> layers) {
  Impl& m = *impl_;
  if (layers.size() != m.options.texture_layers.size()) {
    return fail(fmt::format("{} texture layers given, the scene has {}", layers.size(),
                            m.options.texture_layers.size()));
  }
  for (size_t i = 0; i < layers.size(); ++i) {
    layers[i].tiles = m.layer_loaders.empty() ? nullptr : m.layer_loaders[i].get();
  }
  std::vector<render::TextureLayer> kept = layers;
  RELIEF_CHECK(m.renderer->set_texture_layers(std::move(layers)));
  for (render::TextureLayer& l : kept) l.tiles = nullptr;
  m.options.texture_layers = std::move(kept);
  return {};
}

Result<FrameReport> Scene::draw(const lod::Camera& camera, render::RenderTarget& target,
                                const std::function<void()>& before_drawing) {
  Impl& m = *impl_;
  const lod::View view = RELIEF_TRY(lod::make_view(camera));
  FrameReport report;
  report.camera = camera;
  const auto start = m.clock.now();
  const uint64_t faults_before = thread_page_faults();
  if (m.frozen && m.drawn) {  // the last frame's pins stay: no begin_frame()
    const lod::RefinedMesh* refined = m.last_refined ? &*m.last_refined : nullptr;
    if (before_drawing) before_drawing();
    report.draw = RELIEF_TRY(m.draw_selection(view, m.last, target, refined));
    if (m.hints) RELIEF_CHECK(m.draw_hints(view, m.last, target, report, *this));
    report.frame_seconds = seconds_between(start, m.clock.now());
    report.cpu_seconds = report.frame_seconds - report.draw.gpu_seconds;
    report.page_faults = thread_page_faults() - faults_before;
    report.selection = m.last.stats;
    if (refined) report.refine = refined->stats;
    m.previous.reset();  // no motion to prefetch along when thawed
    return report;
  }
  m.terrain->begin_frame();
  lod::SelectionOptions so = m.options.selection;
  if (m.feeds_back()) so.also_split = m.split_feedback.for_selection(view, *m.terrain);
  m.admitted.clear();
  if (m.loader && m.options.uploads_per_frame > 0) so.drawable_now = m.upload_budget();
  lod::Selection selection = RELIEF_TRY(lod::select_quads(view, *m.terrain, so));
  RELIEF_CHECK(m.prefetch_along_motion(camera));
  if (m.loader && m.options.radius_tiles > 0) {
    m.loader->begin_frame();  // the pager's requests replace the view's
    auto requested = stream::request_radius(*m.terrain, *m.store, view.eye, m.options.radius_tiles);
    if (!requested) return std::unexpected(requested.error());
  }
  m.terrain->end_frame();
  report.select_seconds = seconds_between(start, m.clock.now());
  std::optional<lod::RefinedMesh> refined;
  bool wants_more = false;  // the next frame splits more
  if (m.edge_marks()) {
    lod::RefineOptions ro;
    ro.pixel_error = m.options.selection.pixel_error;
    ro.variant = m.options.refine_variant;
    ro.cache = m.refine_cache.get();
    ro.history = &m.refine_history;
    ro.executor = m.refine_threads.get();
    if (m.options.refine_on_gpu && !m.gpu_criteria) {
      m.gpu_criteria = RELIEF_TRY(render::GlRefineCriteria::create());
    }
    ro.criteria = m.gpu_criteria.get();
    refined = RELIEF_TRY(lod::refine(view, *m.terrain, selection, ro));
    // SceneOptions::split_feedback, interactive frames: what this frame's
    // refinement wanted split, the next frames split (complete frames stay a
    // function of their camera). Not
    // while data is missing: quads then stop coarse for want of their
    // children's tiles (already requested), not for the selection's bound.
    if (m.feeds_back() && selection.stats.waiting == 0 && !refined->stats.split_wanted.empty()) {
      m.split_feedback.record(view, *m.terrain, refined->stats);
      wants_more = true;
    }
    report.refine = refined->stats;
    report.refine_cache_tiles = m.refine_cache->tiles();
    report.refine_cache_bytes = m.refine_cache->bytes();
  }
  if (before_drawing) before_drawing();
  const render::FrameStats preloaded = RELIEF_TRY(m.renderer->preload_elevation(m.admitted));
  report.draw =
      RELIEF_TRY(m.draw_selection(view, selection, target, refined ? &*refined : nullptr));
  report.draw.uploads += preloaded.uploads;
  report.draw.texture_bytes += preloaded.texture_bytes;
  report.draw.prepare_seconds += preloaded.prepare_seconds;
  if (m.hints) RELIEF_CHECK(m.draw_hints(view, selection, target, report, *this));
  report.frame_seconds = seconds_between(start, m.clock.now());
  report.cpu_seconds = report.frame_seconds - report.draw.gpu_seconds;
  report.page_faults = thread_page_faults() - faults_before;
  report.selection = selection.stats;
  report.complete = selection.stats.waiting == 0 && selection.stats.deferred == 0 && !wants_more &&
                    report.draw.texture_misses == 0 && report.hint_tiles_pending == 0;
  report.draws_more =
      wants_more || selection.stats.deferred > 0 || report.draw.layer_tiles_processed > 0;
  if (m.imagery_loader) {
    const stream::LoaderStats is = m.imagery_loader->stats();
    report.complete =
        report.complete && is.queued == 0 && is.in_flight == 0 && is.misses == m.imagery_misses;
    m.imagery_misses = is.misses;
  }
  report.cached_bytes = m.cached_bytes(report.draw);
  m.last = std::move(selection);
  m.last_refined = std::move(refined);
  m.previous = camera;
  m.drawn = true;
  return report;
}

void Scene::set_prefetch_camera(std::optional<lod::Camera> camera) {
  impl_->prefetch_camera = camera;
}

Result<uint32_t> Scene::request(const lod::Camera& camera) {
  Impl& m = *impl_;
  assert(m.loader);  // interactive scenes only
  const lod::View view = RELIEF_TRY(lod::make_view(camera));
  m.terrain->begin_frame();
  lod::SelectionOptions so = m.options.selection;
  if (m.feeds_back()) so.also_split = m.split_feedback.for_selection(view, *m.terrain);
  const lod::Selection selection = RELIEF_TRY(lod::select_quads(view, *m.terrain, so));
  RELIEF_CHECK(m.prefetch_along_motion(camera));
  m.terrain->end_frame();
  return selection.stats.waiting;
}

uint64_t Scene::changes() const {
  std::lock_guard lock(impl_->changes->mutex);
  return impl_->changes->count;
}

bool Scene::wait_for_change(uint64_t seen, double seconds) const {
  Changes& c = *impl_->changes;
  std::unique_lock lock(c.mutex);
  return c.changed.wait_for(lock, std::chrono::duration<double>(std::max(0.0, seconds)),
                            [&] { return c.count != seen; });
}

void Scene::cut() {
  impl_->previous.reset();
}

const SceneOptions& Scene::options() const {
  return impl_->options;
}
void Scene::set_pixel_error(double pixels) {
  assert(pixels > 0);
  impl_->options.selection.pixel_error = pixels;
}
void Scene::set_render_options(const render::RenderOptions& options) {
  impl_->options.render = options;
}
void Scene::set_selection_frozen(bool frozen) {
  impl_->frozen = frozen;
}
bool Scene::selection_frozen() const {
  return impl_->frozen;
}
lod::TerrainModel& Scene::terrain() {
  return *impl_->terrain;
}
const lod::Selection& Scene::last_selection() const {
  return impl_->last;
}
const lod::RefinedMesh* Scene::last_refined() const {
  return impl_->last_refined ? &*impl_->last_refined : nullptr;
}

const std::vector<TargetHint>& Scene::last_hints() const {
  return impl_->last_hints;
}

TargetHints* Scene::target_hints() {
  return impl_->hints.get();
}

Result<lod::MeasuredError> Scene::measure_last_frame(const lod::Camera& camera, int samples) {
  const lod::View view = RELIEF_TRY(lod::make_view(camera));
  // Interactive frames never wait for I/O: no tile is read to measure them.
  if (!impl_->store) return lod::MeasuredError{};  // the bare ellipsoid: no data to miss
  return lod::measure_screen_error(view, *impl_->terrain, impl_->last,
                                   impl_->store->manifest().extent, samples, last_refined(),
                                   !impl_->options.interactive);
}

Result<std::vector<std::optional<double>>> Scene::measure_last_frame_at(
    const lod::Camera& camera, std::span<const lod::DataPoint> points) {
  const lod::View view = RELIEF_TRY(lod::make_view(camera));
  if (!impl_->store) return std::vector<std::optional<double>>(points.size());  // no data
  return lod::measure_screen_error_at(view, *impl_->terrain, impl_->last, points, last_refined());
}

stream::TileLoader* Scene::elevation_loader() {
  return impl_->loader.get();
}
stream::TileLoader* Scene::imagery_loader() {
  return impl_->imagery_loader.get();
}

}  // namespace relief::view
