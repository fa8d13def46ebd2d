// The split criterion of a diamond (refine.h): pixels() on the CPU, or the
// classes a CriterionEvaluator gave every diamond at once.
#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "angle_bound_range.h"
#include "refiner.h"
#include "relief/geo/ellipsoid.h"
#include "relief/lod/criterion_evaluator.h"

namespace relief::lod::refinement {

// The split criterion's value for the part of diamond d inside quad q: the
// screen bound of its error in a box around it and its descendants (nested
// in its parents' boxes, so the value never grows from parent to child).
//
// Unless `exact`, the value returned is only on the same side of the
// threshold as the criterion's (the mesh depends on nothing else): bounds
// from the ball's centre settle most diamonds (angle_bound_range.h), the
// exact bound the others. With `out`, only the distance bound's shortcut.
double Refiner::pixels(int q, GridPoint p, uint32_t slot, const Diamond& d, Criterion* out,
                       bool exact) {
  const Quad& quad = quads_[static_cast<size_t>(q)];
  if (quad.criteria && !out && !exact) {  // evaluated elsewhere, every diamond at once
    const auto c = static_cast<CriterionClass>(quad.criteria[slot]);
    if (c == CriterionClass::kUnder) return 0;
    if (c == CriterionClass::kOver) return INFINITY;
    ++stats_.marks_near;
  }
  const int32_t n = grid_.n();
  double error = 0, lo = 0, hi = 0;
  if (quad.errors) {
    const DiamondError& e = quad.errors->at[slot];
    error = e.error;
    lo = e.lo;
    hi = e.hi;
  }
  const int32_t r = d.reach();
  double edge = 0;
  if (const SideEdges* sides = quad.edges.get()) {
    const std::array<SideMax, 4>& e = sides->side;
    if (!e[0].empty() && p.x - r <= 0) edge = std::max<double>(edge, e[0].max(p.y - r, p.y + r));
    if (!e[1].empty() && p.x + r >= 2 * n)
      edge = std::max<double>(edge, e[1].max(p.y - r, p.y + r));
    if (!e[2].empty() && p.y - r <= 0) edge = std::max<double>(edge, e[2].max(p.x - r, p.x + r));
    if (!e[3].empty() && p.y + r >= n) edge = std::max<double>(edge, e[3].max(p.x - r, p.x + r));
  }
  const double theta = d.hypotenuse() * quad.cell * kDegree;
  const double pad = quad.level_error + edge + kArc * theta * theta / 8;
  const double metres = error + pad;
  const double lon = quad.bounds.west + p.x * quad.cell, lat = quad.bounds.north - p.y * quad.cell;
  const geo::GeoBox area{lon - r * quad.cell, lat - r * quad.cell, lon + r * quad.cell,
                         lat + r * quad.cell};
  // The centre's ECEF position (geo::to_ecef's) from the grid's directions
  // by the angle sums, up to rounding: nanometres, in kRounding.
  const SinCos &x = quad.steps[p.x], &y = quad.steps[p.y];
  const double sin_lon = quad.west.s * x.c + quad.west.c * x.s;
  const double cos_lon = quad.west.c * x.c - quad.west.s * x.s;
  const double sin_lat = quad.north.s * y.c - quad.north.c * y.s;
  const double cos_lat = quad.north.c * y.c + quad.north.s * y.s;
  const double h = (lo + hi) / 2;
  const double normal = quad.normals[static_cast<size_t>(p.y)];
  const Vec3 c{(normal + h) * cos_lat * cos_lon, (normal + h) * cos_lat * sin_lon,
               (normal * (1 - geo::wgs84::kFirstEccentricitySquared) + h) * sin_lat};
  const double radius =
      kArc * std::sqrt(2.0) * r * quad.cell * kDegree + (hi - lo) / 2 + pad + kRounding;
  // Most diamonds are far below the threshold: the distance bound of
  // vertical_error_pixels, from a nearer point than the box's, settles them.
  // Without margins to record, its test (K m / (|c - eye| - sqrt(3) r) <= t)
  // squared, without a root or a division: they were most of the time of
  // this test, on the critical path. It may fail where the one below would
  // pass (rounding): the exact criterion decides those.
  const Vec3 to_centre = c - view_.eye;
  if (!out && !exact) {
    const double reach = quick_metres_ * metres + std::sqrt(3.0) * radius;
    if (dot(to_centre, to_centre) > reach * reach * (1 + kSafety)) return 0;  // under t
  }
  const double centre_distance = length(to_centre);
  const double near = centre_distance - std::sqrt(3.0) * radius;
  if (near > 0) {
    const double bound = view_.pixels_per_radian * metres * (1 + corner_) / near;
    if (bound <= o_.pixel_error) {
      if (out) *out = {bound, metres, true, near, 0, {}};
      return bound;
    }
  }
  const Box box{c - Vec3{radius, radius, radius}, c + Vec3{radius, radius, radius}};
  const double far = centre_distance + std::sqrt(3.0) * radius;
  if (!exact) {
    // The criterion is min(distance bound, angle bound), or the distance
    // bound alone when a corner is behind the eye (vertical_error_parts).
    const double t = o_.pixel_error;
    const double distance = distance_to(box, view_.eye);
    const double by_distance =
        distance > 0 ? view_.pixels_per_radian * metres * (1 + corner_) / distance : INFINITY;
    VerticalErrorParts parts;
    parts.distance = distance;
    parts.distance_bound = by_distance;
    // Compared with margins: the exact bound may round otherwise. A
    // recorded decision kept by the distance bound needs it under its
    // block's keep_below (margin() then takes the distance alone).
    const double keep = out ? quad.blocks[block_of(p)].keep_below : t;
    if (by_distance <= std::min(t, keep) * (1 - kSafety)) {
      parts.pixels = by_distance;
      if (out) *out = {by_distance, metres, false, near, far, parts};
      return by_distance;
    }
    // A recorded decision takes its margins from the exact terms: margins
    // from the bounds' (valid too) were short more often, and a slow
    // camera reused fewer blocks.
    if (!out) {
      const Vec3 up{cos_lat * cos_lon, cos_lat * sin_lon, sin_lat};
      const AngleBoundRange a =
          angle_bound_range(view_, c, radius, up, 2 * r * quad.cell * kDegree, metres);
      if (a.in_front && a.hi <= t) return a.hi;
      if (a.in_front && a.lo > t && by_distance > t * (1 + kSafety)) {
        return std::min(by_distance, a.lo);
      }
    }
  }
  const VerticalErrorParts e = vertical_error_parts(view_, box, area, metres);
  if (out) *out = {e.pixels, metres, false, near, far, e};
  return e.pixels;
}

// RefineOptions::criteria: every diamond's criterion of every quad
// evaluated by `evaluator` (into `classes`, which must outlive the
// refinement), each quad's inputs as pixels() reads them.
Status Refiner::evaluate_criteria(CriterionEvaluator& evaluator,
                                  std::vector<std::vector<uint8_t>>& classes) {
  if (grid_.classes() == 0) return {};  // nothing to decide but the roots
  const int32_t n = grid_.n();
  const int k = grid_.k();
  std::vector<uint32_t> offsets;
  for (int c = 0; c <= grid_.classes(); ++c) offsets.push_back(grid_.class_offset(c));
  std::vector<CriterionQuad> in(quads_.size());
  // Per quad: the steps, then the spreads (kept here while evaluated).
  std::vector<std::vector<double>> tables(quads_.size());
  for (size_t i = 0; i < quads_.size(); ++i) {
    const Quad& q = quads_[i];
    CriterionQuad& c = in[i];
    c.west = q.bounds.west;
    c.north = q.bounds.north;
    c.cell = q.cell;
    c.level_error = q.level_error;
    if (q.errors) {
      c.errors = {reinterpret_cast<const uint8_t*>(q.errors->at.data()), q.errors->bytes()};
      c.errors_owner = q.errors;
    }
    if (q.edges) {
      for (size_t side = 0; side < 4; ++side) c.sides[side] = q.edges->side[side].values();
    }
    c.west_sin = q.west.s;
    c.west_cos = q.west.c;
    c.north_sin = q.north.s;
    c.north_cos = q.north.c;
    std::vector<double>& t = tables[i];
    for (int32_t j = 0; j <= 2 * n; ++j) t.insert(t.end(), {q.steps[j].s, q.steps[j].c});
    // The spread of area_normals() over a diamond's area of half-side
    // reach() cells: 3h (diagonals, class 2j) or 2s (axis, class 2j - 1).
    for (int cls = 0; cls < grid_.classes(); ++cls) {
      const int32_t reach = cls % 2 == 0 ? 3 << (cls / 2) : 2 << (cls / 2 + 1);
      const double spread = std::min(2 * reach * q.cell * kDegree, kPi);
      t.insert(t.end(), {std::cos(spread), std::sin(spread)});
    }
    const auto all = std::span<const double>(t);
    c.steps = all.first(static_cast<size_t>(2 * (2 * n + 1)));
    c.spreads = all.subspan(c.steps.size());
    c.normals = q.normals;
  }
  CriterionFrame f;
  f.view = &view_;
  f.pixel_error = o_.pixel_error;
  f.k = k;
  f.class_offsets = offsets;
  f.arc = kArc;
  f.rounding = kRounding;
  RELIEF_CHECK(evaluator.evaluate(f, in, classes));
  for (size_t i = 0; i < quads_.size(); ++i) {
    if (classes[i].size() < offsets.back()) {
      return fail(fmt::format("refine: the criterion evaluator gave {} classes for {} diamonds",
                              classes[i].size(), offsets.back()));
    }
    quads_[i].criteria = classes[i].data();
  }
  return {};
}

}  // namespace relief::lod::refinement
