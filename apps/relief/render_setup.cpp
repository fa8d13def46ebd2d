#include "render_setup.h"

#include <algorithm>
#include <cstdio>
#include <limits>

#include <fmt/format.h>

#include "detector_options.h"
#include "elevation_options.h"
#include "relief/base/file_io.h"
#include "relief/base/units.h"
#include "relief/pipeline/fused_elevation.h"
#include "relief/render/terrain_renderer.h"
#include "relief/tiles/codec.h"
#include "relief/view/memory_budget.h"

namespace relief::cli {

namespace {

Result<tiles::Store> open_kind(const std::string& path, tiles::DatasetKind kind, const char* role,
                               const StoreAccess& access = {},
                               std::shared_ptr<net::DiskCache>* disk_cache = nullptr) {
  tiles::Store s = RELIEF_TRY(open_store(path, access, disk_cache));
  if (s.manifest().kind != kind) {
    return fail(fmt::format("{}: holds {} data; {} must be an {} store", path,
                            tiles::to_string(s.manifest().kind), role, tiles::to_string(kind)));
  }
  return s;
}

Result<uint64_t> byte_option(const Args& args, const char* name, uint64_t fallback) {
  auto text = args.get(name);
  if (!text) return fallback;
  auto bytes = parse_byte_size(*text);
  if (!bytes) return fail(fmt::format("{}: {}", name, bytes.error().message));
  return *bytes;
}

}  // namespace

Result<tiles::Store> fuse_elevation_options(const Args& args, const std::string& first_name,
                                            tiles::Store first, const StoreAccess& access) {
  const std::vector<std::string> more = args.get_all("--elevation");
  auto mode = pipeline::FuseMode::First;
  if (auto text = args.get("--fuse")) {
    if (*text == "mean") {
      mode = pipeline::FuseMode::Blend;
    } else if (*text != "first") {
      return fail("--fuse: '" + *text + "' is none of first, mean");
    }
  }
  // One weight per layer (STORE, then each --elevation), checked as `relief
  // fuse --weights` checks its own (pipeline::fuse_weights).
  std::vector<double> weights;
  if (auto text = args.get("--weights")) {
    if (mode != pipeline::FuseMode::Blend) {
      return fail("--weights: weighs the mean of the layers; give --fuse mean");
    }
    weights = RELIEF_TRY(parse_numbers("--weights", *text));
    weights = RELIEF_TRY(pipeline::fuse_weights(weights, 1 + more.size(), "elevation layers"));
  }
  if (more.empty()) return first;
  std::vector<pipeline::ElevationLayer> layers;
  layers.push_back({first_name, std::move(first)});
  for (const std::string& path : more) {
    layers.push_back(
        {path, RELIEF_TRY(open_kind(path, tiles::DatasetKind::Elevation, "--elevation", access))});
  }
  ThreadExecutor executor;
  return pipeline::fuse_elevation_layers(std::move(layers), mode, executor, std::move(weights));
}

Result<tiles::Store> open_elevation(const Args& args, const std::string& path,
                                    pipeline::ElevationProcessing elevation,
                                    const StoreAccess& access,
                                    std::shared_ptr<net::DiskCache>* disk_cache) {
  tiles::Store store =
      RELIEF_TRY(open_kind(path, tiles::DatasetKind::Elevation, "STORE", access, disk_cache));
  store = RELIEF_TRY(fuse_elevation_options(args, path, std::move(store), access));
  if (elevation.empty()) return store;
  ThreadExecutor executor;
  const std::string name = store.root().string();
  return pipeline::process_elevation(std::move(store), name, std::move(elevation), executor);
}

Result<LayerOptions> take_layer_options(std::vector<std::string>& argv) {
  LayerOptions layers;
  layers.textures = RELIEF_TRY(take_texture_layers(argv));
  layers.elevation = RELIEF_TRY(take_elevation_processing(argv));
  return layers;
}

std::string help_with_layer_options(const char* help) {
  std::string text = help;
  text.replace(text.find("%TEXTURE%"), 9, std::string(kElevationOptionsHelp) + kTextureOptionsHelp);
  return text;
}

std::vector<OptionSpec> with_scene_options(std::vector<OptionSpec> own) {
  for (const char* name : {"--imagery",       "--detect-level",  "--detect-sensitivity",
                           "--elevation",     "--fuse",          "--weights",
                           "--camera",        "--look-at",       "--size",
                           "--fov",           "--pixel-error",   "--exaggeration",
                           "--lod",           "--sky",           "--gpu-budget",
                           "--memory-budget", "--cache",         "--cache-size",
                           "--loader-nice",   "--refine-threads"}) {
    own.emplace_back(name);
  }
  own.emplace_back("--detect", "", false);
  return own;
}

Result<RenderSetup> parse_render_setup(const Args& args, TextureLayers textures,
                                       pipeline::ElevationProcessing elevation) {
  const bool textured = !textures.layers.empty();
  if (args.positional().size() > 1 || (args.positional().empty() && !textured)) {
    return fail(textured ? "expected at most one elevation STORE"
                         : "expected one elevation STORE (or --texture layers)");
  }
  RenderSetup s;
  s.textures = std::move(textures);
  s.detect = args.has("--detect");
  s.detector = RELIEF_TRY(parse_detector_params(args, "--detect-level", "--detect-sensitivity"));
  if (s.detect && std::none_of(s.textures.layers.begin(), s.textures.layers.end(),
                               [](const render::TextureLayer& l) {
                                 return l.store->manifest().kind == tiles::DatasetKind::Sar;
                               })) {
    return fail("--detect: needs a SAR texture layer (--texture SAR_STORE)");
  }
  if (auto size = args.get("--size")) {
    const auto [width, height] = RELIEF_TRY(parse_width_height("--size", *size, 16384));
    s.width = width;
    s.height = height;
  }
  for (auto [name, target, lo, hi] : {std::tuple{"--fov", &s.fov, 1.0, 170.0},
                                      std::tuple{"--pixel-error", &s.pixel_error, 0.05, 1000.0},
                                      std::tuple{"--exaggeration", &s.exaggeration, 0.0, 100.0}}) {
    auto v = RELIEF_TRY(args.get_double(name));
    if (v) {
      if (!(*v >= lo && *v <= hi))
        return fail(fmt::format("{}: must be in [{}, {}]", name, lo, hi));
      *target = *v;
    }
  }
  if (auto level = RELIEF_TRY(args.get_int("--mesh-level", 0, 8))) s.mesh_level = *level;
  if (auto nice = RELIEF_TRY(args.get_int("--loader-nice", 0, 19))) s.loader_nice = *nice;
  if (auto threads = RELIEF_TRY(args.get_int("--refine-threads", 0, 64))) {
    s.refine_threads = static_cast<unsigned>(*threads);
  }
  if (auto lod = args.get("--lod")) {
    if (*lod == "quads") {
      s.lod_mode = lod::LodMode::quads;
    } else if (*lod == "edge-marks-gl") {
      s.refine_on_gpu = true;
    } else if (*lod == "edge-marks" || *lod == "edge-marks-bottom-up") {
      if (*lod == "edge-marks-bottom-up") s.refine_variant = lod::RefineVariant::kBottomUp;
    } else {
      return fail("--lod: '" + *lod +
                  "' is none of edge-marks, edge-marks-bottom-up, edge-marks-gl, quads");
    }
  }
  s.full_resolution = args.has("--full-resolution");
  s.sky = render::RenderOptions{}.sky;
  if (auto text = args.get("--sky")) {
    auto c = RELIEF_TRY(parse_numbers("--sky", *text, 3));
    for (int i = 0; i < 3; ++i) {
      if (!(c[i] >= 0 && c[i] <= 255)) {
        return fail(fmt::format("--sky: '{}': each of R,G,B must be in 0..255", *text));
      }
      s.sky[i] = static_cast<float>(c[i] / 255);
    }
  }
  s.gpu_budget = RELIEF_TRY(byte_option(args, "--gpu-budget", s.gpu_budget));
  s.gpu_budget_given = args.has("--gpu-budget");
  s.memory_budget = RELIEF_TRY(byte_option(args, "--memory-budget", s.memory_budget));
  // Refused now, before any GL context: the split itself comes with the scene.
  RELIEF_CHECK(view::split_memory_budget(s.memory_budget, view::CacheUse{}));

  StoreAccess access;
  access.cache_bytes = RELIEF_TRY(byte_option(args, "--cache-size", access.cache_bytes));
  access.cache_dir = args.get("--cache").value_or("");
  if (auto ms = RELIEF_TRY(args.get_double("--simulate-latency"))) {
    if (!(*ms >= 0 && *ms <= 60000)) return fail("--simulate-latency: must be in [0, 60000] ms");
    access.link.latency = std::chrono::microseconds(static_cast<int64_t>(*ms * 1000));
  }
  if (auto mbit = RELIEF_TRY(args.get_double("--simulate-bandwidth"))) {
    if (!(*mbit > 0)) return fail("--simulate-bandwidth: must be > 0 Mbit/s");
    access.link.bits_per_second = *mbit * 1e6;
  }
  s.has_elevation = !args.positional().empty();
  if (s.has_elevation) {
    s.store = RELIEF_TRY(
        open_elevation(args, args.positional()[0], std::move(elevation), access, &s.disk_cache));
  } else if (!args.get_all("--elevation").empty()) {
    return fail("--elevation: fuses with an elevation STORE, and none was given");
  } else if (!elevation.empty()) {
    return fail("--elevation-op: processes an elevation STORE, and none was given");
  }
  s.disk_cache_budget = access.cache_bytes;
  if (auto path = args.get("--imagery")) {
    s.imagery = RELIEF_TRY(open_kind(*path, tiles::DatasetKind::Imagery, "--imagery"));
    if (textured) {  // the bottom layer, as it is
      s.textures.stores.push_front(std::move(*s.imagery));
      s.textures.paths.insert(s.textures.paths.begin(), *path);
      render::TextureLayer bottom;
      bottom.store = &s.textures.stores.front();
      s.textures.layers.insert(s.textures.layers.begin(), bottom);
      s.imagery.reset();
    }
  }
  return s;
}

view::SceneOptions scene_options(const RenderSetup& setup) {
  view::SceneOptions so;
  so.selection.pixel_error = setup.pixel_error;
  so.selection.full_resolution = setup.full_resolution;
  if (setup.imagery) so.selection.texture = &*setup.imagery;
  so.texture_layers = setup.textures.layers;
  for (const render::TextureLayer& l : so.texture_layers) {  // split down to the finest texture
    if (!so.selection.texture ||
        l.store->manifest().max_level > so.selection.texture->manifest().max_level) {
      so.selection.texture = l.store;
    }
  }
  so.detect = setup.detect;
  so.detector = setup.detector;
  so.full_resolution = setup.full_resolution;
  so.mesh_level = setup.mesh_level;
  so.selection.mode = setup.lod_mode;
  so.refine_variant = setup.refine_variant;
  so.refine_on_gpu = setup.refine_on_gpu;
  so.refine_threads = setup.refine_threads.value_or(0);  // one per core unless given
  so.gpu_budget = setup.gpu_budget;
  so.gpu_budget_given = setup.gpu_budget_given;
  so.memory_budget = setup.memory_budget;
  so.loader.worker_nice = setup.loader_nice;
  so.render.exaggeration = static_cast<float>(setup.exaggeration);
  so.render.sky = setup.sky;
  return so;
}

namespace {

constexpr double kNoLowerBound = std::numeric_limits<double>::lowest();

struct Bound {
  const char* what;
  double lo, hi;
  bool lo_open = false, hi_open = false;  // whether lo, hi themselves are excluded

  bool holds(double v) const {
    return (lo_open ? v > lo : v >= lo) && (hi_open ? v < hi : v <= hi);  // false for NaN
  }
};

// Each value of `v` within its bound; a value outside is a typo or a unit
// mix-up (radians, lat/lon swapped), named in the error rather than rendered.
Status check_bounds(const char* option, const std::vector<double>& v,
                    std::initializer_list<Bound> bounds) {
  size_t i = 0;
  for (const Bound& b : bounds) {
    if (!b.holds(v[i])) {
      const std::string allowed = b.lo == kNoLowerBound
                                      ? fmt::format("at most {}", b.hi)
                                      : fmt::format("in {}{}, {}{}", b.lo_open ? '(' : '[', b.lo,
                                                    b.hi, b.hi_open ? ')' : ']');
      return fail(fmt::format("{}: {} {} is not {}", option, b.what, v[i], allowed));
    }
    ++i;
  }
  return {};
}

// Longitudes may be given in [-180, 360): 0-360 is common for global data.
constexpr Bound kLon{"longitude", -180, 360, false, true}, kLat{"latitude", -90, 90};
constexpr Bound kHeading{"heading", -360, 360}, kPitch{"pitch", -90, 90};
// Heights and ranges up to 100 000 km: the whole Earth fits the view well before.
constexpr double kFarthest = 1e8;

double normalized_longitude(double lon) {
  return lon > 180 ? lon - 360 : lon;
}

}  // namespace

Result<lod::Camera> camera_from_values(const std::string& where, const std::vector<double>& v,
                                       const RenderSetup& s) {
  // Heights below -1000 m (inside the ellipsoid) are refused by lod::make_view.
  const Bound height{"height (m)", kNoLowerBound, kFarthest};
  RELIEF_CHECK(
      check_bounds(where.c_str(), v, {kLon, kLat, height, kHeading, kPitch, {"roll", -180, 180}}));
  return lod::Camera{
      normalized_longitude(v[0]), v[1], v[2], v[3], v[4], v[5], s.fov, s.width, s.height};
}

Result<lod::Camera> parse_camera(const Args& args, const RenderSetup& s) {
  lod::Camera camera;
  const char* option = args.get("--camera") ? "--camera" : "--look-at";
  if (auto c = args.get("--camera")) {
    const std::vector<double> values = RELIEF_TRY(parse_numbers("--camera", *c, 6));
    camera = RELIEF_TRY(camera_from_values("--camera", values, s));
  } else {
    auto v = RELIEF_TRY(parse_numbers("--look-at", *args.get("--look-at"), 6));
    // Targets as deep as the ocean floor (bathymetry), seen from any positive range.
    const Bound height{"height (m)", -12000, kFarthest}, range{"range (m)", 0, kFarthest, true};
    RELIEF_CHECK(check_bounds("--look-at", v, {kLon, kLat, height, range, kHeading, kPitch}));
    camera = lod::look_at(normalized_longitude(v[0]), v[1], v[2], v[3], v[4], v[5], s.fov, s.width,
                          s.height);
  }
  if (auto view = lod::make_view(camera); !view) {
    return fail(fmt::format("{}: {}", option, view.error().message));
  }
  return camera;
}

Result<std::optional<int>> error_samples(const Args& args) {
  auto n = RELIEF_TRY(args.get_int("--error-samples", 0, 1000000));
  if (n && !args.get("--stats")) return fail("--error-samples: only with --stats");
  return n;
}

Status write_png(const std::string& path, std::span<const uint8_t> rgba, int width, int height) {
  tiles::Raster image(tiles::SampleType::UInt8, 4, width, height);
  std::copy(rgba.begin(), rgba.end(), image.u8().begin());
  auto png = RELIEF_TRY(tiles::encode(image, tiles::CodecOptions{tiles::Codec::Png}));
  return write_file_atomic(path, png);
}

Status write_json(const std::string& path, const std::string& text) {
  return write_file_atomic(path, std::as_bytes(std::span(text.data(), text.size())));
}

}  // namespace relief::cli
