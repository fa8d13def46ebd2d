// bench/drawtime: draw-time processing of a SAR texture layer (issue 14,
// docs/gpu-processing.md "Draw-time processing"). An interactive scene of the
// store alone on the bare ellipsoid, straight down on its extent's centre
// from RANGE metres (the view filled with data), is drawn until complete
// (every layer tile resident and processed: the warm-up). Then, per run, the
// layer's parameters change (Scene::set_texture_layers; runs alternate two
// parameter sets so each really changes something) and frames are drawn
// until one is complete again: a complete frame draws every quad with its own
// composite of the current parameters, so no tile of the old ones is left.
// Per chain: wall time from the change to the end of that frame (steady
// clock), frames needed, layer tiles processed, the renderer's GPU processing
// seconds (chain, colour map and composite, to glFinish) and processed samples
// per second, the frames' wait for the renderer's CPU workers, and the
// process's CPU time over the change (all threads); then the CPU path (gpuprocess::run_chain_cpu, a
// ThreadExecutor on every core) on the tiles the complete frame drew, processing only (tiles
// already decoded in memory, no colour map, no upload). Medians of RUNS runs.
// With a fourth argument, the rows are also appended to that file as a
// markdown table. Every chain runs on the GPU path; the target's chain runs
// again processed on the CPU (render::ProcessOn::cpu, the automatic choice
// on llvmpipe). CHAINS=NAME,... in the environment: only the chains whose
// names start so; BUDGET_MS=MS: the frames' processing budget (default 100).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "relief/base/clock.h"
#include "relief/base/parallel.h"
#include "relief/gpuprocess/chain.h"
#include "relief/view/scene.h"

using namespace relief;

namespace {

struct StepText {
  std::string op;
  std::vector<std::string> params;
};

// A row: a chain (parameters for the store's finest level) and the second
// parameter set runs alternate with (`range_scale`: the second set narrows
// the colour map's range instead, for filters without a parameter that keeps
// their cost).
struct Case {
  std::string name, change;
  std::vector<StepText> a, b;
  double range_scale = 1;
  render::ProcessOn where = render::ProcessOn::gpu;
};

std::vector<Case> cases() {
  const auto lee3 = StepText{"lee", {"radius=3"}};
  const auto schlick = [](const char* d) {
    return StepText{"ext-schlick", {"max_radius=4", std::string("d=") + d}};
  };
  const auto alone = [](std::string op, std::vector<std::string> a, std::vector<std::string> b,
                        std::string change) {
    const std::string name = op + (a.empty() ? "" : " " + a.front());
    return Case{name, std::move(change), {{op, std::move(a)}}, {{op, std::move(b)}}, 1};
  };
  const auto range_only = [](std::string op, std::vector<std::string> a) {
    const std::string name = op + " " + a.front();
    return Case{name, "range max x0.8", {{op, a}}, {{op, a}}, 0.8};
  };
  return {
      {"lee radius=3 + linear",
       "linear sigmas 3 / 2.5",
       {lee3, {"linear", {"sigmas=3"}}},
       {lee3, {"linear", {"sigmas=2.5"}}},
       1},
      // The same chain processed on the CPU (--process-on cpu, the automatic
      // choice on llvmpipe), mapped and composited on the GPU.
      {"lee radius=3 + linear, on the CPU",
       "linear sigmas 3 / 2.5",
       {lee3, {"linear", {"sigmas=3"}}},
       {lee3, {"linear", {"sigmas=2.5"}}},
       1,
       render::ProcessOn::cpu},
      {"lee radius=3 + ext-schlick max_radius=4",
       "ext-schlick d 0.5 / 0.3",
       {lee3, schlick("0.5")},
       {lee3, schlick("0.3")},
       1},
      range_only("mean", {"radius=3"}),
      range_only("median", {"radius=3"}),
      alone("gauss", {"radius=3", "sigma=1.2"}, {"radius=3", "sigma=1.5"}, "sigma 1.2 / 1.5"),
      alone("lee", {"radius=3", "looks=1"}, {"radius=3", "looks=2"}, "looks 1 / 2"),
      alone("kuan", {"radius=3", "looks=1"}, {"radius=3", "looks=2"}, "looks 1 / 2"),
      alone("frost", {"radius=3", "deramp=0.1"}, {"radius=3", "deramp=0.2"}, "deramp 0.1 / 0.2"),
      alone("gamma-map", {"radius=3", "looks=1"}, {"radius=3", "looks=2"}, "looks 1 / 2"),
      alone("wavelet", {"levels=2", "k=1"}, {"levels=2", "k=1.5"}, "k 1 / 1.5"),
      alone("linear", {"sigmas=3"}, {"sigmas=2.5"}, "sigmas 3 / 2.5"),
      alone("log", {"c=100"}, {"c=50"}, "c 100 / 50"),
      alone("gamma", {"gamma=0.5"}, {"gamma=0.4"}, "gamma 0.5 / 0.4"),
      alone("ext-schlick", {"max_radius=8", "d=0.5"}, {"max_radius=8", "d=0.3"}, "d 0.5 / 0.3"),
      alone("ext-reinhard-devlin", {"max_radius=8", "d=0.5"}, {"max_radius=8", "d=0.3"},
            "d 0.5 / 0.3"),
  };
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : (v[n / 2 - 1] + v[n / 2]) / 2;
}

// The layer as `relief render --texture` makes it: SAR amplitudes mapped
// over [min, mean + 3 std], a dynamic-range mapping's output over [0, 1].
Result<render::TextureLayer> make_layer(const tiles::Store& store,
                                        const std::vector<StepText>& steps, double range_scale,
                                        render::ProcessOn where) {
  render::TextureLayer l;
  l.store = &store;
  l.process_on = where;
  for (const StepText& s : steps)
    l.chain.steps.push_back(RELIEF_TRY(gpuprocess::make_step(s.op, s.params)));
  RELIEF_CHECK(gpuprocess::check_chain_for(l.chain, store.manifest(), "SAR store"));
  const tiles::SampleStats& st = store.manifest().stats;
  l.range_min = static_cast<float>(st.min);
  l.range_max = static_cast<float>(std::min(st.max, st.mean + 3 * st.stddev));
  if (l.chain.steps.back().op->needs_global_stats) l.range_min = 0, l.range_max = 1;
  l.range_max = static_cast<float>(l.range_min + (l.range_max - l.range_min) * range_scale);
  RELIEF_CHECK(render::check_texture_layer(l));
  return l;
}

struct Row {
  double wall_ms = 0, frames = 0, tiles = 0, gpu_ms = 0, gpu_msps = 0, redraw_ms = 0;
  // The process's CPU time over the change (every thread: llvmpipe's, the
  // renderer's workers, this one), and the frames' wait for the workers.
  double process_cpu_ms = 0, wait_ms = 0;
  double cpu_ms = 0, cpu_msps = 0;
  size_t cpu_tiles = 0;
};

using Steady = std::chrono::steady_clock;
double ms_since(Steady::time_point t0) {
  return std::chrono::duration<double, std::milli>(Steady::now() - t0).count();
}

// CPU time of the whole process, every thread, in ms: on a loaded machine a
// steadier figure than the wall clock.
double process_cpu_ms() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) * 1e3 + static_cast<double>(t.tv_nsec) / 1e6;
}

// Frames until one is complete; a frame that processed nothing and is not
// complete waits for tiles, so the loop pauses briefly then. Returns the
// frames drawn, adding their processing to `tiles` and `seconds`.
Result<int> draw_until_complete(view::Scene& scene, const lod::Camera& camera,
                                render::RenderTarget& target, uint64_t& tiles, double& seconds,
                                double& waited) {
  for (int frame = 1; frame <= 5000; ++frame) {
    const view::FrameReport f = RELIEF_TRY(scene.draw(camera, target));
    tiles += f.draw.layer_tiles_processed;
    seconds += f.draw.processing_seconds;
    waited += f.draw.processing_wait_seconds;
    if (f.complete) return frame;
    if (f.draw.layer_tiles_processed == 0)
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  return fail("no complete frame after 5000 frames");
}

// The texture keys the last frame drew (composite_for in terrain_composites.cpp:
// each quad's tile at the store's finest level or above, where it has data).
std::vector<geo::TileKey> drawn_tiles(const view::Scene& scene, const tiles::Store& store) {
  std::set<geo::TileKey> keys;
  const tiles::Manifest& m = store.manifest();
  for (const lod::SelectedQuad& q : scene.last_selection().quads) {
    const int level = std::min(q.key.level, m.max_level), up = q.key.level - level;
    const geo::TileKey k{level, q.key.x >> up, q.key.y >> up};
    if (level >= m.min_level && store.has_tile(k)) keys.insert(k);
  }
  return {keys.begin(), keys.end()};
}

Result<Row> measure(const tiles::Store& store, const Case& c, const lod::Camera& camera,
                    render::RenderTarget& target, int runs) {
  const render::TextureLayer a = RELIEF_TRY(make_layer(store, c.a, 1, c.where));
  const render::TextureLayer b = RELIEF_TRY(make_layer(store, c.b, c.range_scale, c.where));
  view::SceneOptions o;
  o.interactive = true;
  // BUDGET_MS: the frames' processing budget (RenderOptions), e.g. to see
  // the CPU path finish in one frame on a loaded machine, where the
  // workers' estimate exceeds the default 100 ms.
  if (const char* budget = std::getenv("BUDGET_MS")) {
    o.render.processing_per_frame = std::atof(budget) / 1e3;
  }
  o.texture_layers = {a};
  o.selection.texture = &store;
  auto scene = RELIEF_TRY(view::Scene::create(nullptr, nullptr, o, steady_clock()));
  // Warm-up: every tile loaded and processed, the operators' programs compiled.
  uint64_t tiles = 0;
  double seconds = 0, waited = 0;
  RELIEF_TRY(draw_until_complete(*scene, camera, target, tiles, seconds, waited));
  Row row;
  {
    const view::FrameReport again = RELIEF_TRY(scene->draw(camera, target));
    if (!again.complete || again.draw.layer_tiles_processed != 0) {
      return fail("a redraw of the complete frame processed tiles again");
    }
    row.redraw_ms = again.frame_seconds * 1e3;
  }
  const double interior =
      static_cast<double>(store.grid().width()) * static_cast<double>(store.grid().height());
  std::vector<double> wall, frames, processed, gpu, rate, cpu_time, wait;
  for (int r = 0; r < runs; ++r) {
    tiles = 0, seconds = 0, waited = 0;
    const auto t0 = Steady::now();
    const double c0 = process_cpu_ms();
    RELIEF_CHECK(scene->set_texture_layers({r % 2 == 0 ? b : a}));
    const int n = RELIEF_TRY(draw_until_complete(*scene, camera, target, tiles, seconds, waited));
    wall.push_back(ms_since(t0));
    cpu_time.push_back(process_cpu_ms() - c0);
    wait.push_back(waited * 1e3);
    frames.push_back(n);
    processed.push_back(static_cast<double>(tiles));
    gpu.push_back(seconds * 1e3);
    rate.push_back(static_cast<double>(tiles) * interior / seconds / 1e6);
  }
  row.wall_ms = median(wall), row.frames = median(frames), row.tiles = median(processed);
  row.gpu_ms = median(gpu), row.gpu_msps = median(rate);
  row.process_cpu_ms = median(cpu_time), row.wait_ms = median(wait);

  // The CPU path on the tiles the complete frame drew, decoded beforehand.
  const std::vector<geo::TileKey> keys = drawn_tiles(*scene, store);
  const tiles::Manifest& m = store.manifest();
  std::vector<tiles::Tile> input;
  std::vector<gpuprocess::OperatorChain> chains;
  for (const geo::TileKey& k : keys) {
    input.push_back(RELIEF_TRY(store.read_tile(k)));
    chains.push_back(gpuprocess::scale_chain(a.chain, std::ldexp(1.0, m.max_level - k.level)));
  }
  const process::GlobalStats stats{m.stats.min, m.stats.max, m.stats.mean, m.stats.stddev};
  ThreadExecutor executor;
  std::vector<double> cpu;
  for (int r = 0; r < runs; ++r) {
    const auto t0 = Steady::now();
    for (size_t i = 0; i < input.size(); ++i) {
      const auto out =
          gpuprocess::run_chain_cpu(chains[i], input[i].raster, m.border, &stats, executor);
      if (!out) return fail(out.error().message);
    }
    cpu.push_back(ms_since(t0));
  }
  row.cpu_tiles = keys.size();
  row.cpu_ms = median(cpu);
  row.cpu_msps = static_cast<double>(keys.size()) * interior / (row.cpu_ms / 1e3) / 1e6;
  return row;
}

Result<std::pair<int, int>> parse_size(const std::string& text) {
  int w = 0, h = 0;
  char x = 0, extra = 0;
  if (std::sscanf(text.c_str(), "%d%c%d%c", &w, &x, &h, &extra) != 3 || x != 'x' || w < 16 ||
      h < 16 || w > 8192 || h > 8192) {
    return fail(text + ": not a size WxH (16..8192)");
  }
  return std::pair{w, h};
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 4 && argc != 5) {
    std::fprintf(stderr, "usage: drawtime_bench SAR_STORE WxH RUNS [MARKDOWN_ROWS_OUT]\n");
    return 2;
  }
  const auto size = parse_size(argv[2]);
  const int runs = std::atoi(argv[3]);
  if (!size || runs < 1) {
    std::fprintf(stderr, "%s\n",
                 !size ? size.error().message.c_str() : "RUNS: a positive number of runs");
    return 2;
  }
  FILE* markdown = argc == 5 ? std::fopen(argv[4], "a") : nullptr;
  if (argc == 5 && !markdown) {
    std::fprintf(stderr, "%s: cannot open for appending\n", argv[4]);
    return 1;
  }
  auto store = tiles::Store::open(argv[1]);
  if (!store) {
    std::fprintf(stderr, "%s\n", store.error().message.c_str());
    return 1;
  }
  if (store->manifest().kind != tiles::DatasetKind::Sar) {
    std::fprintf(stderr, "%s: not a SAR store\n", argv[1]);
    return 1;
  }
  auto context = render::GlContext::create_headless();
  if (!context) {
    std::fprintf(stderr, "%s\n", context.error().message.c_str());
    return 1;
  }
  auto target = render::make_offscreen_target(size->first, size->second);
  if (!target) {
    std::fprintf(stderr, "%s\n", target.error().message.c_str());
    return 1;
  }
  // Straight down on the extent's centre, from low enough that the data
  // fills the view (the image is ~1.2 km square, rotated ~14 degrees).
  const geo::GeoBox& e = store->manifest().extent;
  constexpr double kRange = 520;
  const lod::Camera camera = lod::look_at((e.west + e.east) / 2, (e.south + e.north) / 2, 0, kRange,
                                          0, -90, 60, size->first, size->second);
  std::printf(
      "renderer: %s; %dx%d, straight down on %.5f,%.5f from %.0f m, pixel error 1; %d runs, "
      "medians; CPU: %u threads\n",
      (*context)->renderer().c_str(), size->first, size->second, camera.lon, camera.lat, kRange,
      runs, ThreadExecutor().concurrency());
  std::printf("%-42s %-22s %9s %6s %6s %9s %9s %9s %9s %9s %7s %9s %9s\n", "chain", "change",
              "wall ms", "frames", "tiles", "gpu ms", "gpu Ms/s", "cpu ms", "cpu Ms/s", "redraw ms",
              "gpu/cpu", "wait ms", "proc cpu");
  bool failed = false;
  // CHAINS=NAME,NAME: only the chains whose names start with one of them.
  const char* only = std::getenv("CHAINS");
  const auto chosen = [only](const std::string& name) {
    if (!only || !*only) return true;
    std::string list = only;
    for (size_t start = 0; start <= list.size();) {
      const size_t end = std::min(list.find(',', start), list.size());
      if (end > start && name.starts_with(list.substr(start, end - start))) return true;
      start = end + 1;
    }
    return false;
  };
  for (const Case& c : cases()) {
    if (!chosen(c.name)) continue;
    auto row = measure(*store, c, camera, **target, runs);
    if (!row) {
      std::fprintf(stderr, "%s: %s\n", c.name.c_str(), row.error().message.c_str());
      failed = true;
      continue;
    }
    const Row& r = *row;
    std::printf("%-42s %-22s %9.1f %6.0f %6.0f %9.1f %9.2f %9.1f %9.2f %9.1f %6.2fx %9.1f %9.1f\n",
                c.name.c_str(), c.change.c_str(), r.wall_ms, r.frames, r.tiles, r.gpu_ms,
                r.gpu_msps, r.cpu_ms, r.cpu_msps, r.redraw_ms, r.gpu_msps / r.cpu_msps, r.wait_ms,
                r.process_cpu_ms);
    if (r.tiles != static_cast<double>(r.cpu_tiles)) {
      std::printf("  note: the change processed %.0f layer tiles, the complete frame draws %zu\n",
                  r.tiles, r.cpu_tiles);
    }
    if (markdown) {
      std::fprintf(markdown,
                   "| %s | %s | %.1f ms | %.0f | %.0f | %.1f ms, %.1f Ms/s | %.1f ms, %.1f Ms/s | "
                   "%.2f× | %.1f ms | %.1f ms | %.1f ms |\n",
                   c.name.c_str(), c.change.c_str(), r.wall_ms, r.frames, r.tiles, r.gpu_ms,
                   r.gpu_msps, r.cpu_ms, r.cpu_msps, r.gpu_msps / r.cpu_msps, r.redraw_ms,
                   r.wait_ms, r.process_cpu_ms);
    }
  }
  if (markdown && std::fclose(markdown) != 0) {
    std::fprintf(stderr, "%s: write failed\n", argv[4]);
    return 1;
  }
  return failed ? 1 : 0;
}
