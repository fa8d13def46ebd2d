// The walks over the diamonds: top-down (from the coarsest, a split bringing
// its children) and bottom-up (every mark, finest first). Each decides a mark
// by the split criterion and makes the splits a split forces (refine.h); in
// lanes, those forced into another lane's quads go through its inbox.
#include <algorithm>
#include <cassert>

#include "refiner.h"

namespace relief::lod::refinement {

// Top-down: diamonds decided ahead of the one whose data is fetched.
constexpr size_t kAhead = 8;

// The first diamonds of every quad (their children come by splits).
void Refiner::seed_top_down() {
  const int32_t n = grid_.n();
  for (size_t i = 0; i < quads_.size(); ++i) {
    for (const GridPoint p : {GridPoint{n / 2, 0}, GridPoint{3 * n / 2, 0}, GridPoint{n / 2, n},
                              GridPoint{3 * n / 2, n}, GridPoint{0, n / 2}, GridPoint{n, n / 2},
                              GridPoint{2 * n, n / 2}}) {
      work_.push_back({static_cast<int>(i), p});
    }
  }
}

void Refiner::run_generations() {
  // Split children of splits made while preparing are in work_ already.
  // Generation by generation (the children of this one's splits go to
  // the next): the final marks do not depend on the order (a child's
  // criterion never exceeds its parent's), and in this order the errors
  // and marks of the diamond kAhead places on can be fetched while this
  // one is decided. Depth first, a child was decided right after it was
  // pushed: reading its diamond's error missed the caches.
  while (!work_.empty()) {
    generation_.swap(work_);
    for (size_t i = 0; i < generation_.size(); ++i) {
      if (i + kAhead < generation_.size()) prefetch(generation_[i + kAhead]);
      decide(generation_[i].quad, generation_[i].p);
    }
    generation_.clear();
    if (lanes_) {
      send_splits();
      take_splits();
    }
  }
}

void Refiner::bottom_up() {
  // Finest diamonds first over all quads: class c of a quad of level l has
  // the size of class c + 2 (deepest - l) of the deepest quads.
  int last = 0;
  for (size_t i = 0; i < quads_.size(); ++i) {
    last = std::max(last, grid_.classes() - 1 + 2 * (deepest_ - level(static_cast<int>(i))));
  }
  for (int g = 0; g <= last; ++g) {
    for (size_t i = 0; i < quads_.size(); ++i) {
      const int q = static_cast<int>(i);
      const int c = g - 2 * (deepest_ - level(q));
      if (c < 0 || c >= grid_.classes()) continue;
      grid_.for_each_in_class(c, [&](GridPoint p) { decide(q, p); });
    }
  }
}

// Evaluates the split criterion of an undecided mark (for both quads when
// it lies on their shared side) and splits it or keeps it.
void Refiner::decide(int q, GridPoint p) {
  const Diamond d = grid_.diamond(p);
  if (!MarkGrid::splittable(d)) return;
  const uint32_t slot = grid_.slot(p);
  uint8_t& m = mark_at(q, slot);
  if (m != kUnknown) return;
  ++stats_.marks_evaluated;
  Located across_at;
  const Located* other = mirror(q, p, across_at) ? &across_at : nullptr;
  // The criterion's parts only where record() keeps them (in members:
  // zeroing two of them per call took a quarter of this function).
  Criterion &own = own_, &across = across_;
  auto recorded = [&](int quad, Criterion& c) {
    return history_ && mine(quad) && quads_[static_cast<size_t>(quad)].recording ? &c : nullptr;
  };
  double px = pixels(q, p, slot, d, recorded(q, own));
  bool stuck = blocked(q, p, d);
  // The half across a side shared with a finer quad may be a sample's
  // side there (the finer quad's mark is blocked then): that half is the
  // coarser quad's full mesh already, nothing to split.
  const Diamond od = other ? grid_.diamond(other->p) : Diamond{};
  const bool halves = other && MarkGrid::splittable(od);
  const uint32_t other_slot = halves ? grid_.slot(other->p) : 0;
  if (halves) {
    px = std::max(px, pixels(other->quad, other->p, other_slot, od, recorded(other->quad, across)));
    stuck |= blocked(other->quad, other->p, od);
  }
  if (px > o_.pixel_error && stuck) {  // the statistics want the value itself
    px = pixels(q, p, slot, d, nullptr, true);
    if (halves) {
      px = std::max(px, pixels(other->quad, other->p, other_slot, od, nullptr, true));
    }
  }
  if (history_) {
    record(q, p, own, stuck);
    if (halves && mine(other->quad)) record(other->quad, other->p, across, stuck);
  }
  if (px > o_.pixel_error && !stuck) {
    split(q, p);
    return;
  }
  if (px > o_.pixel_error) {
    if (lanes_) {  // the lane across may count it too: counted once by key
      const Located key = other && other->quad < q ? *other : Located{q, p};
      unresolved_keys_.push_back(uint64_t(uint32_t(key.quad)) << 32 | pack(key.p, false));
    } else {
      ++stats_.unresolved;
    }
    stats_.max_unresolved_pixels = std::max(stats_.max_unresolved_pixels, px);
    want_split_across(q, p, d);
    if (other) want_split_across(other->quad, other->p, grid_.diamond(other->p));
  }
  m = kKept;
  // (A sample's side across, never split, has no mark.) Another lane's
  // quad decides its half itself, the same way.
  if (halves && mine(other->quad) && marks_.get(other->quad, other_slot) == kUnknown) {
    mark_at(other->quad, other_slot) = kKept;
  }
}

// The same edge mark in the quad across the border, if one is selected:
// true and `out`. (Not an optional<Located>: returned in two registers,
// the compiler assembled it on the stack from a 32-bit and an 8-bit store
// and read it back in one 64-bit load, which stalled store forwarding.)
bool Refiner::mirror(int q, GridPoint p, Located& out) {
  const uint8_t sides = grid_.sides(p);
  if (!sides) return false;
  const int side = (sides & kWest) ? 0 : (sides & kEast) ? 1 : (sides & kNorth) ? 2 : 3;
  const Quad& from = quads_[static_cast<size_t>(q)];
  const int64_t gx = from.ox + p.x * from.scale, gy = from.oy + p.y * from.scale;
  const int32_t n = grid_.n();
  for (int k = 0; k < 2; ++k) {
    const int32_t j = from.selected->neighbours[static_cast<size_t>(2 * side + k)];
    if (j < 0) continue;
    const Quad& to = quads_[static_cast<size_t>(j)];
    int64_t along, max;
    GridPoint at;
    if (side < 2) {
      along = gy - to.oy;
      max = n;
    } else {
      along = ((gx - to.ox) % globe_width_ + globe_width_) % globe_width_;
      max = 2 * n;
    }
    if (along % to.scale) continue;  // between the other quad's grid points
    along /= to.scale;
    if (along < 0 || along > max) continue;
    const int32_t a = static_cast<int32_t>(along);
    at = side == 0   ? GridPoint{2 * n, a}
         : side == 1 ? GridPoint{0, a}
         : side == 2 ? GridPoint{a, n}
                     : GridPoint{a, 0};
    if (grid_.diamond(at).kind == MarkKind::kVertex) return false;
    out = Located{j, at};
    return true;
  }
  return false;
}

// Splits a diamond and, to keep the mesh conforming, its parents (forced
// splits), the same edge in the neighbouring quad, and so on.
void Refiner::split(int q, GridPoint p) {
  stack_.push_back({q, p});
  while (!stack_.empty()) {
    const Located l = stack_.back();
    stack_.pop_back();
    if (grid_.is_corner(l.p)) continue;  // a half's corner: always a vertex
    uint8_t& m = mark(l.quad, l.p);
    if (m == kSplit) continue;
    m = kSplit;
    const Diamond d = grid_.diamond(l.p);
    assert(MarkGrid::splittable(d) && !blocked(l.quad, l.p, d));
    // The children of a diagonal of h are axis diamonds of s = h, those
    // of an axis diamond of s diagonals of h = s / 2 (always splittable).
    if (top_down_ && (d.kind != MarkKind::kDiagonal || d.size >= 2)) {
      for (const GridPoint& c : d.children(l.p)) {
        if (!grid_.inside(c)) continue;
        work_.push_back({l.quad, c});
      }
    }
    if (Located other; mirror(l.quad, l.p, other)) {
      if (mine(other.quad)) {
        stack_.push_back(other);
      } else {
        outbox_[lanes_->owner[static_cast<size_t>(other.quad)]].push_back(other);
      }
    }
    for (const GridPoint& a : d.apexes) {
      if (grid_.inside(a)) stack_.push_back({l.quad, a});
    }
  }
}

// Diamonds that can never split: along a side shared with a coarser quad
// that is drawn, a sample's side of that quad (s <= 2 here) and the cells
// whose split would need one. (Against a culled quad, vertices may go
// anywhere: they take the parent's data all the same.)
bool Refiner::blocked(int q, GridPoint p, const Diamond& d) const {
  const uint8_t coarse = quads_[static_cast<size_t>(q)].blocking;
  if (!coarse) return false;
  const int32_t n = grid_.n();
  if (d.kind == MarkKind::kDiagonal) {
    if (d.size != 1) return false;
    return ((coarse & kWest) && p.x == 1) || ((coarse & kEast) && p.x == 2 * n - 1) ||
           ((coarse & kNorth) && p.y == 1) || ((coarse & kSouth) && p.y == n - 1);
  }
  if (d.size > 2) return false;
  return ((coarse & kWest) && p.x == 0) || ((coarse & kEast) && p.x == 2 * n) ||
         ((coarse & kNorth) && p.y == 0) || ((coarse & kSouth) && p.y == n);
}

// Records the coarser neighbour whose side blocks diamond d of quad q.
void Refiner::want_split_across(int q, GridPoint p, const Diamond& d) {
  if (!blocked(q, p, d)) return;
  const SelectedQuad& s = selection_.quads[static_cast<size_t>(q)];
  const int32_t n = grid_.n();
  const bool near[4] = {p.x <= 1, p.x >= 2 * n - 1, p.y <= 1, p.y >= n - 1};
  const int offset[4][2] = {{-1, 0}, {1, 0}, {0, -1}, {0, 1}};
  for (int side = 0; side < 4; ++side) {
    if (!near[side] || !(quads_[static_cast<size_t>(q)].blocking & kSideBits[side])) continue;
    // The coarser neighbour is one level up (restricted quadtree), culled or not.
    const auto across = s.key.neighbour(offset[side][0], offset[side][1]);
    if (!across || !across->parent()) continue;
    auto& wanted = stats_.split_wanted;
    if (std::find(wanted.begin(), wanted.end(), *across->parent()) == wanted.end()) {
      wanted.push_back(*across->parent());
    }
  }
}

// One round of a lane: what its inbox holds and what that splits, until
// neither its inbox nor its work has more. Splits sent to other lanes after
// their round ended wait for the next round (refine() runs rounds until no
// inbox has any): no lane waits for another, so the rounds finish whatever
// the executor runs at once.
void Refiner::run_lane() {
  take_splits();
  run_generations();
  send_splits();
}

// Lanes: the splits forced into other lanes' quads, to their inboxes.
void Refiner::send_splits() {
  for (size_t t = 0; t < outbox_.size(); ++t) {
    std::vector<Located>& out = outbox_[t];
    if (out.empty()) continue;
    Lanes::Inbox& in = *lanes_->inboxes[t];
    {
      std::lock_guard lock(in.mutex);
      in.splits.insert(in.splits.end(), out.begin(), out.end());
      in.any.store(true, std::memory_order_release);
    }
    out.clear();
  }
}

// Lanes: the splits other lanes forced into this one's quads, made here.
void Refiner::take_splits() {
  Lanes::Inbox& in = *lanes_->inboxes[lane_];
  if (!in.any.load(std::memory_order_acquire)) return;
  {
    std::lock_guard lock(in.mutex);
    received_.swap(in.splits);
    in.any.store(false, std::memory_order_relaxed);
  }
  for (const Located& l : received_) split(l.quad, l.p);
  received_.clear();
}

}  // namespace relief::lod::refinement
