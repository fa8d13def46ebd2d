#pragma once
// The viewer: position and orientation on the WGS84 ellipsoid, field of view
// and viewport, and what follows from them (the view basis in ECEF, the
// frustum, projection to pixels). Everything in double precision; the
// renderer subtracts the eye position in double before going to float.
#include <array>

#include "relief/base/result.h"
#include "relief/lod/vec.h"

namespace relief::lod {

struct Camera {
  double lon = 0, lat = 0, height = 1000;     // degrees, metres above the ellipsoid
  double heading = 0, pitch = -30, roll = 0;  // degrees: from north clockwise; down < 0
  double fov_y = 60;                          // vertical field of view, degrees
  int width = 800, height_px = 600;           // viewport, pixels
};

// A camera looking at (lon, lat, height) from `range` metres away, with the
// given heading and pitch (pitch < 0 looks down at the target).
Camera look_at(double lon, double lat, double height, double range, double heading, double pitch,
               double fov_y, int width, int height_px);

struct Plane {
  Vec3 normal;   // pointing into the frustum
  double d = 0;  // dot(normal, p) + d >= 0 inside
};

// A rectangle of pixels, origin top-left.
struct PixelRect {
  int x = 0, y = 0, width = 0, height = 0;
  bool empty() const { return width <= 0 || height <= 0; }
  bool operator==(const PixelRect&) const = default;
};

struct View {
  Vec3 eye;                 // ECEF, metres
  Vec3 right, up, forward;  // unit basis, ECEF
  double tan_half_x = 0, tan_half_y = 0;
  double pixels_per_radian = 0;  // height_px / (2 tan(fov_y / 2)): the K of the error bound
  int width = 0, height = 0;
  double near = 0.1;
  std::array<Plane, 5> planes;  // near, left, right, bottom, top (no far: reversed-Z, infinite)
  // The part of the width x height view this view draws (a sort-first tile,
  // one display of a wall), empty for all of it. Everything above stays the
  // whole view's: its level of detail and its frustum, so that the tiles of
  // a view assemble into exactly its image. The renderer draws the window
  // into a target of the window's size (an off-axis sub-frustum).
  PixelRect window;

  // Screen position (pixels, origin top-left) of an ECEF point in front of the eye.
  bool project(const Vec3& p, double& sx, double& sy) const;
};

// Fails for a camera inside the ellipsoid, a bad field of view or viewport;
// the message names no option: the caller knows where the camera came from.
Result<View> make_view(const Camera& camera);

// `view` drawing only `window`, which must lie inside it (a one-line error
// naming the rectangle otherwise).
Result<View> with_window(const View& view, const PixelRect& window);
// The window's own (off-axis) frustum: near, left, right, bottom, top; the
// whole view's planes without a window.
std::array<Plane, 5> window_planes(const View& view);
// Whether an ECEF box lies entirely outside these planes.
bool outside(const std::array<Plane, 5>& planes, const Vec3& lo, const Vec3& hi);

}  // namespace relief::lod
