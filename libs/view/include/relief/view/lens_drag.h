#pragma once
// Lenses moved on the terrain (the viewer drags them with the mouse): which
// lens's circle holds a point on the ground, and a lens moved to a new centre.
// Circles are measured as the renderer draws them (docs/gpu-processing.md,
// "Lenses"): metres on the local tangent plane at the lens centre.
#include <cstddef>
#include <optional>
#include <vector>

#include "relief/render/terrain_renderer.h"

namespace relief::view {

// A lens of the scene's texture layers: layers[layer].lenses[lens].
struct LensRef {
  size_t layer = 0, lens = 0;
  bool operator==(const LensRef&) const = default;
};

// Metres from a lens centre (lon0, lat0) to (lon, lat) on the tangent plane
// there, the distance the lens pass compares with the radius.
double lens_distance_m(double lon0, double lat0, double lon, double lat);

// The lens whose circle holds (lon, lat); of several, the one whose centre is
// nearest relative to its radius (the upper layer's on a tie). nullopt: none.
std::optional<LensRef> lens_at(const std::vector<render::TextureLayer>& layers, double lon,
                               double lat);

}  // namespace relief::view
