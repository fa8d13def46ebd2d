#pragma once
// Geometry the control modes share: a camera's orientation as ECEF vectors
// (the same basis lod::make_view builds), a camera from such vectors, level
// moves over the ellipsoid and rotations.
#include <optional>

#include "relief/lod/camera.h"
#include "relief/view/controller.h"

namespace relief::view::controls {

inline constexpr double kDeg = 3.14159265358979323846 / 180;

struct Frame {
  lod::Vec3 eye, forward, right, up;
};

// The eye and view basis of `camera`, as lod::make_view computes them.
Frame frame_of(const lod::Camera& camera);
// `camera` (field of view and viewport kept) moved to `eye` and turned to look
// along `forward` with `up` as the top of the screen (heading, pitch and roll
// read in the eye's own local frame).
lod::Camera with_frame(lod::Camera camera, const lod::Vec3& eye, const lod::Vec3& forward,
                       const lod::Vec3& up);
// `camera` moved `forward_m` along its heading and `right_m` to the right,
// level (its height unchanged), keeping its direction over the ground.
lod::Camera move_level(lod::Camera camera, double forward_m, double right_m);
// `v` rotated by `angle` radians about the unit `axis` (right-handed).
lod::Vec3 rotate(const lod::Vec3& v, const lod::Vec3& axis, double angle);
// The ground height at (lon, lat): the ellipsoid where none is resident.
double ground_or_zero(const Ground& ground, double lon, double lat);

}  // namespace relief::view::controls
