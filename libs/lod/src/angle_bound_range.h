#pragma once
// Cheap bounds of the angle bound that vertical_error_parts() (screen_error.h)
// computes, f m (S + T C) / z_min, for the cube that refinement puts around a
// diamond's ball (refine_criterion.cpp, pixels()). The exact value takes the
// box's eight corners (a square root and a division each) and five trigonometric
// calls; most diamonds are far enough from the threshold that these bounds,
// from the cube's centre alone, settle which side of it they are on, and
// refinement evaluates the exact value only for the others: the same
// decisions, so the same mesh.
//
// With d = centre - eye and (x, y, z) its camera coordinates, the corners are
// d + (+-h, +-h, +-h):
// - z_min = z - h |forward|_1 exactly (in real arithmetic);
// - T = max over corners of |p_xy| / z is at most (|x| + h |right|_1, |y| +
//   h |up|_1) / z_min, and at least its value at the centre: |p_xy| / z is
//   quasi-convex where z > 0 (its sublevel sets are cones), so its largest
//   value over the cube is at a corner, and the centre is in the cube;
// - S and C, the largest |sin| and |cos| of the angle between the view
//   direction and the normals within `spread` of the centre's, lie between
//   their value at the centre's normal and that plus the spread (both are
//   1-Lipschitz; S is the largest sin over [theta - spread, theta + spread]
//   in [0, pi], C the largest |cos|).
// Every term is widened for rounding (of this computation and the exact one,
// which differ by the way they get the normal: within 1e-12 here).
#include "relief/lod/camera.h"
#include "relief/lod/vec.h"

namespace relief::lod {

struct AngleBoundRange {
  // Every corner surely in front of the eye; otherwise the exact bound may be
  // the distance bound alone (a corner behind), and nothing below holds.
  bool in_front = false;
  double lo = 0, hi = 0;  // lo <= f m (S + T C) / z_min <= hi
  // The terms' bounds, for decisions' margins (refine_margins.cpp, margin()).
  double z_lo = 0, z_hi = 0, t_lo = 0, t_hi = 0, s_lo = 0, s_hi = 0, c_lo = 0, c_hi = 0;
};

// `centre` and `half`: the cube's centre (ECEF) and half side, as the exact
// bound gets them (Box{centre - half, centre + half}); `normal`: the unit
// geodetic normal at the area's centre within 1e-12 of up_at(); `spread`:
// half the area's width plus height, radians, within 1e-12.
AngleBoundRange angle_bound_range(const View& view, const Vec3& centre, double half,
                                  const Vec3& normal, double spread, double metres);

}  // namespace relief::lod
