// Texture layers (TextureLayer): each quad's layers processed (on the GPU,
// or on the CPU's workers) and composited into one texture, made for the
// current parameters, an ancestor's meanwhile.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <set>

#include <fmt/format.h>

#include "gl_terrain_renderer.h"
#include "relief/render/render_target.h"

namespace relief::render {
namespace {

using geo::TileKey;
using Clock = std::chrono::steady_clock;

}  // namespace

// Texture layers (the other create()): composited per quad on the GPU.
Status GlTerrainRenderer::init_layers(std::vector<TextureLayer> layers) {
  if (layers.empty()) return {};
  gpu_ = RELIEF_TRY(gpuprocess::GpuProcessor::create());
  compositor_ = RELIEF_TRY(gpuprocess::Compositor::create());
  software_ = software_rasteriser();
  for (size_t i = 0; i < layers.size(); ++i) {
    if (layers[i].store->manifest().max_level > layers[reference_].store->manifest().max_level) {
      reference_ = i;
    }
  }
  owned_layer_tiles_.resize(layers.size());
  return set_texture_layers(std::move(layers));
}

Status GlTerrainRenderer::set_texture_layers(std::vector<TextureLayer> layers) {
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

void GlTerrainRenderer::set_on_processed(std::function<void()> on_processed) {
  on_processed_ = std::move(on_processed);
}

// The composite of a quad's texture layers: that of its tile at the
// reference layer's finest level or above, else (its layers' tiles not at
// hand yet: requested) of its nearest ancestor whose tiles are, made now if
// not cached for the current parameters. Never one of older parameters.
Result<std::pair<lod::DataWindow, std::optional<int>>> GlTerrainRenderer::composite_for(
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

// The composite of texture key `a` for the current parameters: cached, or
// made from the layers' tiles when every one is at hand (otherwise those
// missing are requested, and nothing is made).
Result<GlTerrainRenderer::Made> GlTerrainRenderer::make_composite(const TileKey& a, double priority,
                                                                  gl::Uploads& uploads,
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
  const int slot = RELIEF_TRY(slots_.insert({a, true, version_}, width, height, nullptr, uploads));
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
Status GlTerrainRenderer::process_view_on_cpu(const lod::Selection& selection, gl::Uploads& uploads,
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
bool GlTerrainRenderer::on_cpu(const TextureLayer& l) const {
  if (l.chain.steps.empty() || !l.lenses.empty()) return false;
  return l.process_on == ProcessOn::cpu || (l.process_on == ProcessOn::automatic && software_);
}

// Layer i's tile `key` through its chain on the CPU: for stills now (every
// core), for interactive frames by the workers (null until done).
Result<lod::TilePtr> GlTerrainRenderer::process_on_cpu(size_t i, const TileKey& key,
                                                       const lod::TilePtr& tile, double priority) {
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

}  // namespace relief::render
