#pragma once
// Per-quad records for the terrain vertex shader (shaders.h), 22 RGBA32F
// texels each of a buffer texture: what a quad's vertices need besides quad-space (u, v). Only the
// anchors depend on the eye; a view that does not change gives the same
// records, which are then not uploaded again.
#include <cstdint>
#include <unordered_map>

#include "relief/geo/tile_key.h"
#include "relief/lod/selection.h"

namespace relief::render {

enum QuadBits : uint32_t {
  kHasOwn = 1,      // own heights resident (else height 0)
  kHasParent = 2,   // parent heights resident
  kHasImagery = 4,  // imagery resident
  // coarse_sides << 4, coarse_corners << 8, x & 1 << 12, y & 1 << 13,
  // parent_data_sides << 14, parent_data_corners << 18
  // The bits travel as a float texel: with bits up to 22 set alone it is a
  // denormal, which Mesa's llvmpipe did not return intact (heights from the
  // wrong data: gpu_geometry_test); an exponent bit makes it a normal float.
  kNormalFloat = 1u << 30,
};

struct QuadRecord {
  // The quad's corners (north-west, north-east, south-west, south-east) then
  // its parent's: the ECEF point on the ellipsoid minus the eye, and the prime
  // vertical radius there.
  float anchor[8][4];
  float trig[8][4];  // cos lat, sin lat, cos lon, sin lon of the corners
  float own_window[4], parent_window[4], imagery_window[4];  // x0, y0, width, height
  float size[4];      // width, height (degrees), north, south latitude
  uint32_t slots[4];  // layers of own heights, parent heights, imagery; QuadBits
  float shade[4];     // north-south sample spacing, metres; unused
};
static_assert(sizeof(QuadRecord) == 22 * 16, "the shader reads 22 texels per quad");

// How near the eye a quad is, to draw the nearest first: the distance from
// the eye to the centre of its corners less their farthest distance from
// that centre (a quad under the eye comes first however large). An
// estimate for ordering draws, not a bound (terrain rises above the corners).
float nearness(const QuadRecord& r);

class QuadRecords {
 public:
  // The geometry of quad `q` seen from `eye` (windows, layers and their
  // bits are the caller's).
  QuadRecord make(const lod::SelectedQuad& q, const lod::Vec3& eye);

 private:
  // What does not depend on the eye, kept between frames.
  struct Corners {
    lod::Vec3 ecef[8];
    float trig[8][4];
    float radius[8];
  };
  const Corners& corners(const geo::TileKey& key);
  static constexpr size_t kMaxCached = 200000;
  std::unordered_map<geo::TileKey, Corners, geo::TileKeyHash> cache_;
};

}  // namespace relief::render
