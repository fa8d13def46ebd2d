#pragma once
// What `relief render` needs for a still and for a path: the stores and the
// options shared by both, parsed once with one-line errors.
#include <array>
#include <optional>
#include <string>
#include <vector>

#include "args.h"
#include "open_store.h"
#include "relief/pipeline/processed_elevation.h"
#include "relief/tiles/store.h"
#include "relief/view/scene.h"
#include "texture_options.h"

namespace relief::cli {

struct RenderSetup {
  tiles::Store store;  // the elevation store, when has_elevation
  bool has_elevation = true;
  TextureLayers textures;            // --texture layers (docs/gpu-processing.md)
  bool detect = false;               // --detect: hints over the SAR layer (docs/target-hints.md)
  process::DetectorParams detector;  // --detect-level, --detect-sensitivity
  std::optional<tiles::Store> imagery;
  int width = 1024, height = 768;
  double fov = 60, pixel_error = 1, exaggeration = 1;
  int mesh_level = 4;
  lod::LodMode lod_mode = lod::LodMode::edge_marks;
  lod::RefineVariant refine_variant = lod::RefineVariant::kTopDown;
  bool refine_on_gpu = false;  // --lod edge-marks-gl
  bool full_resolution = false;
  std::array<float, 3> sky{};
  uint64_t gpu_budget = uint64_t{1} << 30;
  bool gpu_budget_given = false;  // --gpu-budget: L3 outside the memory budget's split
  // --memory-budget: every tile cache in main memory (view/memory_budget.h).
  uint64_t memory_budget = uint64_t{2} << 30;
  int loader_nice = 0;                         // --loader-nice: LoaderOptions::worker_nice
  std::optional<unsigned> refine_threads;      // --refine-threads (0: one per core)
  std::shared_ptr<net::DiskCache> disk_cache;  // L1, remote stores with --cache only
  uint64_t disk_cache_budget = 0;
};

// The layer options `relief render` and `relief view` take out of their
// arguments before the rest is parsed: the --texture family (repeating, in
// order) and the --elevation-op family.
struct LayerOptions {
  TextureLayers textures;
  pipeline::ElevationProcessing elevation;
};
Result<LayerOptions> take_layer_options(std::vector<std::string>& argv);

// A command's help with both families' help in place of its %TEXTURE%.
std::string help_with_layer_options(const char* help);

// `textures`: the --texture layers (take_texture_layers()); with any, the
// elevation store is optional (they drape on the ellipsoid).
// `own` (a command's options) and the options parse_render_setup() reads,
// which `relief render` and `relief view` share: stores and layers (but the
// --texture family, taken out before), camera, image, level of detail,
// caches, detector hints.
std::vector<OptionSpec> with_scene_options(std::vector<OptionSpec> own);

// `elevation`: the --elevation-op family (take_elevation_processing()),
// applied to the (fused) elevation store when it is opened.
Result<RenderSetup> parse_render_setup(const Args& args, TextureLayers textures = {},
                                       pipeline::ElevationProcessing elevation = {});

// The elevation store, or null (texture layers on the bare ellipsoid).
inline const tiles::Store* elevation_of(const RenderSetup& s) {
  return s.has_elevation ? &s.store : nullptr;
}

// `--elevation STORE` (repeatable), `--fuse first|mean` and `--weights
// W1,W2,...` (the mean's, one per layer): `first` alone, or
// the elevation layers first, then each --elevation, fused at draw time
// (pipeline/fused_elevation.h). Shared by `relief render` and `relief view`.
Result<tiles::Store> fuse_elevation_options(const Args& args, const std::string& first_name,
                                            tiles::Store first, const StoreAccess& access = {});

// The elevation STORE as `relief render` draws it: --elevation layers fused
// (fuse_elevation_options) and the --elevation-op chain applied. What
// `relief export --format quantized-mesh` and `relief serve` give web
// clients too.
Result<tiles::Store> open_elevation(const Args& args, const std::string& path,
                                    pipeline::ElevationProcessing elevation,
                                    const StoreAccess& access = {},
                                    std::shared_ptr<net::DiskCache>* disk_cache = nullptr);

// Scene options of a setup: selection (imagery sets the texture level), mesh,
// GPU budget, drawing.
view::SceneOptions scene_options(const RenderSetup& setup);

// A camera from --camera or --look-at values, with the setup's viewport.
Result<lod::Camera> parse_camera(const Args& args, const RenderSetup& setup);

// --error-samples N (0 to 10^6; only with --stats), if given.
Result<std::optional<int>> error_samples(const Args& args);
// A camera [lon, lat, height, heading, pitch, roll] checked against the same
// bounds as --camera; errors start with `where` (an option or a keyframe).
Result<lod::Camera> camera_from_values(const std::string& where, const std::vector<double>& v,
                                       const RenderSetup& setup);

// Writes RGBA pixels as a PNG, atomically.
Status write_png(const std::string& path, std::span<const uint8_t> rgba, int width, int height);

// Writes JSON text atomically.
Status write_json(const std::string& path, const std::string& text);

}  // namespace relief::cli
