#pragma once
// Draw-time texture layers (docs/gpu-processing.md, "Draw-time processing"):
// each layer's tile with its overlap border goes through the layer's operator
// chain on the GPU (GpuProcessor::run_on_gpu), is mapped through a value range
// and a colour map (single-band layers; RGBA imagery is used as it is), and
// the layers are composited by opacity, first at the bottom, into one
// premultiplied RGBA8 texture that stays on the GPU.
//
// Thread safety: as GpuProcessor (the thread whose GL context is current).
#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <string>

#include "relief/base/result.h"
#include "relief/geo/tile_key.h"
#include "relief/gpuprocess/gpu_processor.h"

namespace relief::gpuprocess {

enum class ColorMap { grey, viridis };

// "grey" or "viridis"; anything else is a one-line error.
Result<ColorMap> parse_colormap(const std::string& name);
const char* to_string(ColorMap map);

// A lens (seed 003 §1.5.2): inside a circle on the ground, a layer's samples
// come from another chain. Samples are merged one by one, so a tile the
// circle's edge crosses is processed by both chains.
struct CompositeLens {
  const OperatorChain* chain = nullptr;  // for the tile's level (scale_chain)
  double lon = 0, lat = 0, radius_m = 0;
};

// Whether a lens's circle may cover samples of `box` (a conservative test).
bool lens_touches(const CompositeLens& lens, const geo::GeoBox& box);

struct CompositeLayer {
  // Float32 single band (processed by `chain`) or UInt8 RGBA, premultiplied
  // (used as it is), with `border` overlap samples on every side.
  const tiles::Raster* tile = nullptr;
  int border = 0;
  const OperatorChain* chain = nullptr;  // for the tile's level (scale_chain); may be empty
  const process::GlobalStats* stats = nullptr;
  float range_min = 0, range_max = 1;  // single band: mapped to the colour map's 0 and 1
  ColorMap colormap = ColorMap::grey;
  float opacity = 1;
  // The part of the tile's interior the composite covers, in interior
  // samples: x0, y0, width, height (the whole tile: 0, 0, its interior size).
  std::array<double, 4> window{};
  // Single band: lenses, and where the tile's interior lies on the ground.
  std::span<const CompositeLens> lenses;
  geo::GeoBox bounds;
};

// The layer pass's colour mapping on the CPU, for a composite made of one
// single-band layer whose tile is the composite's (`values`: the processed
// tile's interior plus a one-sample border, as run_chain_cpu leaves it):
// premultiplied RGBA8 of the same size, nodata transparent. The same float
// arithmetic as the shader; the GPU's conversion to 8 bits may round a
// value on a half level the other way (one level at most).
tiles::Raster map_colours_cpu(const tiles::Raster& values, float range_min, float range_max,
                              ColorMap map, float opacity);

class Compositor {
 public:
  // Needs a current GL 4.5 core context.
  static Result<std::unique_ptr<Compositor>> create();
  ~Compositor();
  Compositor(const Compositor&) = delete;
  Compositor& operator=(const Compositor&) = delete;

  // Composites `layers` (the first at the bottom) into layer `array_layer` of
  // the RGBA8 2-D array texture `array_texture` (a GL name, immutable
  // storage), whose `width` x `height` texels are the composite's interior
  // plus a one-sample border. Nodata (NaN, alpha 0) is transparent.
  Status composite(GpuProcessor& gpu, std::span<const CompositeLayer> layers,
                   uint32_t array_texture, int array_layer, int width, int height);

 private:
  struct Impl;
  explicit Compositor(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace relief::gpuprocess
