// Recording decisions (RefineHistory): each with the motion of the eye and
// the turn of the view within which it stays the same (docs/rendering.md,
// "Reusing decisions").
#include <algorithm>
#include <array>
#include <cmath>

#include "refiner.h"

namespace relief::lod::refinement {

namespace {

// tan(kTurn * budget + kAngleSlack + asin(kMoveShare * budget)) for the
// budgets 2^-4 .. 2^2.
double widening(double budget) {
  static const std::array<double, 7> table = [] {
    std::array<double, 7> t{};
    for (int i = 0; i < 7; ++i) {
      const double b = std::ldexp(1.0, i - 4);
      t[static_cast<size_t>(i)] = std::tan(kTurn * b + kAngleSlack + std::asin(kMoveShare * b));
    }
    return t;
  }();
  return table[static_cast<size_t>(std::clamp(std::ilogb(budget) + 4, 0, 6))];
}

// A decision made now holds within `move` and `turn` of this view: within
// move - moved and turn - turned of a reused block's (triangle inequality).
void allow(Quad::Block& b, double move, double turn) {
  move -= b.moved;
  turn -= b.turned;
  if (move < 0 || turn < 0) {
    b.state.margins = false;
    b.budget_short = true;
    return;
  }
  b.state.move = std::min(b.state.move, move);
  b.state.turn = std::min(b.state.turn, turn);
}

}  // namespace

// Records one half of a decision (QuadDecisions says which) with its margins.
void Refiner::record(int q, GridPoint p, const Criterion& c, bool stuck) {
  Quad& quad = quads_[static_cast<size_t>(q)];
  if (!quad.recording) return;
  const bool over = c.pixels > o_.pixel_error;
  if (over ? stuck : grid_.sides(p) != 0) return;
  Quad::Block& b = quad.blocks[block_of(p)];
  quad.halves.push_back(pack(p, over));
  if (b.reused) b.state.later = true;
  if (!b.state.margins || c.metres <= 0) return;  // 0 metres: 0 pixels from everywhere
  if (over) {
    b.state.highest = std::min(b.state.highest, b.split_over);
  } else {
    b.state.lowest = std::max(b.state.lowest, b.keep_below);
  }
  if (c.quick) {
    keep_distance(b, c.near, c.metres);
  } else {
    margin(b, c.parts, c.metres, c.far);
  }
}

// Reusing decisions: the margins of one criterion (pixels()) of a recording
// quad, as the motion of the eye (metres) and the view's turn (radians)
// within which its decision stays the same. Proof in "Reusing decisions".
//
// Kept by a distance bound f m (1 + t^2) / D <= t: D moves no more than
// the eye does, so the decision holds while the eye moves less than
// D - f m (1 + t^2) / t, whatever the view's direction.
void Refiner::keep_distance(Quad::Block& b, double distance, double metres) {
  const double needed = view_.pixels_per_radian * metres * (1 + corner_) / b.keep_below;
  const double slack = distance * (1 - kSafety) - needed * (1 + kSafety) - kSlackMetres;
  allow(b, slack, INFINITY);
}

// Otherwise, for an eye motion of at most move = kMoveShare * budget * z_min
// and a turn of at most w = kTurn * budget: every corner's depth changes by
// at most move + far * w (far: the largest distance of a corner), the
// angle between a corner's direction and the view direction by at most
// w + asin(move / z_min), that between the view direction and a normal by
// at most w (so S and C by at most w), the box's distance by at most move.
// The criterion's value stays on its side of t when the bound computed with
// every term moved against it does.
void Refiner::margin(Quad::Block& b, const VerticalErrorParts& e, double metres, double far) {
  const bool kept = e.pixels <= o_.pixel_error;
  if (kept && e.distance_bound <= b.keep_below) {
    keep_distance(b, e.distance, metres);
    return;
  }
  if (e.behind) {  // only the distance bound, and it does not do
    b.state.margins = false;
    return;
  }
  const double move = kMoveShare * b.state.budget * e.z_min, turn = kTurn * b.state.budget;
  const double w = turn + kAngleSlack;
  // tan(w + asin(move / z_min)): the angles add by tan(a + b) = (tan a +
  // tan b) / (1 - tan a tan b), with tan a = T.
  const double u = widening(b.state.budget), T = e.tangent;
  const double k = view_.pixels_per_radian * metres;
  bool holds = false;
  if (kept) {  // by the angle bound
    const double z = e.z_min - move - far * turn - kSlackMetres;
    if (z > 0 && T * u < 1) {
      const double s = std::min(1.0, e.sin_bound + w), c = std::min(1.0, e.cos_bound + w);
      holds = k * (s + (T + u) / (1 - T * u) * c) / z <= b.keep_below * (1 - kSafety);
    }
  } else {  // split: both bounds stay over t
    const double z = e.z_min + move + far * turn + kSlackMetres;
    const double s = std::max(0.0, e.sin_bound - w), c = std::max(0.0, e.cos_bound - w);
    const double narrowest = T > u ? (T - u) / (1 + T * u) : 0.0;
    const double t = b.split_over * (1 + kSafety);
    holds = k * (1 + corner_) / (e.distance + move + kSlackMetres) > t &&
            k * (s + narrowest * c) / z > t;
  }
  if (!holds) {
    b.state.margins = false;
    b.budget_short = true;
    return;
  }
  allow(b, move, turn);
}

}  // namespace relief::lod::refinement
