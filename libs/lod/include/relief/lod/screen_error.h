#pragma once
// How far, in pixels, a vertical error can move a point on screen: the
// projection of an object-space error bound that level-of-detail decisions
// compare with the pixel-error threshold.
//
// The error is a segment of `metres` along the geodetic vertical (the mesh
// point above a sample and the sample itself), anywhere in `box` and at a
// point of `area`. With camera coordinates p = (x, y, z) (z along the view
// direction) and screen s = f (x / z, y / z), moving p by d gives
//   ds = (f / z) (d_xy - (p_xy / z) d_z),
// so along the whole segment |ds| <= f |d| (S + T C) / z_min, where S and C
// bound |sin| and |cos| of the angle between the vertical and the view
// direction over the area (its normals lie within a cone around the centre's),
// T bounds |p_xy| / z over the box (attained at a corner: x / z and y / z are
// linear-fractional) and z_min is the box's smallest depth. Seen straight
// down, S and T are small near the centre of the screen and the bound falls
// towards 0; at grazing angles S = 1 and it is the distance bound.
// Independently, a segment of length m at distance >= d subtends at most m / d
// radians and the projection stretches an angle at most f (1 + t^2) times,
// t the tangent of the screen's corner: the bound is the smaller of the two
// (the second also holds for boxes reaching behind the eye).
#include "relief/geo/tile_key.h"
#include "relief/lod/camera.h"
#include "relief/lod/vec.h"

namespace relief::lod {

// The geodetic normals over an area: within `spread` radians of the centre's
// `up` (area_normals()), with the spread's cosine and sine.
struct AreaNormals {
  Vec3 up;
  double cos_spread = 1, sin_spread = 0;
};

// Upper bound of the screen distance between the two ends of a vertical
// segment of length `metres` lying in `box`, at a point of `area`; INFINITY
// when the box holds the eye.
double vertical_error_pixels(const View& view, const Box& box, const geo::GeoBox& area,
                             double metres);

// The same bound with the terms it is made of, for callers that bound how
// far it can move when the view does (refine_margins.cpp, reusing decisions).
struct VerticalErrorParts {
  double pixels = 0;          // vertical_error_pixels()
  double distance = 0;        // from the eye to the box
  double distance_bound = 0;  // f m (1 + t^2) / distance (INFINITY at 0)
  bool behind = false;        // a corner at or behind the eye: the distance bound alone
  // When not behind: the box's smallest depth, its largest tangent T from
  // the view direction, and the bounds S and C of |sin| and |cos|.
  double z_min = 0, tangent = 0, sin_bound = 1, cos_bound = 1;
};
VerticalErrorParts vertical_error_parts(const View& view, const Box& box, const geo::GeoBox& area,
                                        double metres);

// The same, with the area's normals computed once (they cost three sines and
// cosines: TerrainModel::QuadInfo keeps a quad's across frames).
AreaNormals area_normals(const geo::GeoBox& area);
VerticalErrorParts vertical_error_parts(const View& view, const Box& box,
                                        const AreaNormals& normals, double metres);
double vertical_error_pixels(const View& view, const Box& box, const AreaNormals& normals,
                             double metres);

}  // namespace relief::lod
