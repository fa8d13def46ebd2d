#pragma once
// The refiner behind lod::refine() (refine.h): one frame's edge-mark
// refinement of a selection, a class whose parts live in files by what they do:
//
//   refine.cpp            refine(): one frame, start to end
//   refine_prepare.cpp    the quads' terms of the criterion, before any decision
//   refine_reuse.cpp      reusing the last frames' decisions (RefineHistory)
//   refine_lanes.cpp      top-down on several threads (lanes)
//   refine_walk.cpp       the walks (top-down, bottom-up): deciding and splitting marks
//   refine_criterion.cpp  the split criterion: pixels(), or an evaluator's classes
//   refine_margins.cpp    recording decisions with the motion they hold for
//   refine_mesh.cpp       the triangles of the marks
//
// A file calls only into those below it. The caches kept between frames:
// refine_cache.h, refine_history.h.
#include <algorithm>
#include <atomic>
#include <cassert>
#include <cmath>
#include <cstdint>
#include <memory>
#include <mutex>
#include <span>
#include <vector>

#include "diamond_errors.h"
#include "edge_marks.h"
#include "mark_blocks.h"
#include "refine_cache.h"
#include "refine_history.h"
#include "relief/lod/grid_vertex_ids.h"
#include "relief/lod/refine.h"
#include "relief/lod/screen_error.h"
#include "side_edges.h"

namespace relief::lod {

class CriterionEvaluator;

namespace refinement {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDegree = kPi / 180;
// Metres per radian of arc, above every radius of curvature of the ellipsoid
// (6 399 594 m at the poles) plus the highest terrain: the chord between two
// points at the same height is at most this times their angular distance.
constexpr double kArc = 6.41e6;
// Metres added to the radius of a diamond's ball for the rounding of its
// centre's position (computed without trigonometric calls per diamond).
constexpr double kRounding = 1e-3;
constexpr uint8_t kUnknown = 0, kSplit = 1, kKept = 2;
constexpr uint8_t kSideBits[4] = {kWest, kEast, kNorth, kSouth};
// Margins kept against rounding: relative on bounds and distances (their
// rounding is ~1e-15), metres on distances, radians on angles (acos near 0
// loses ~1e-8).
constexpr double kSafety = 1e-9, kSlackMetres = 1e-6, kAngleSlack = 1e-7;

struct SinCos {
  double s = 0, c = 1;
  explicit SinCos(double radians = 0) : s(std::sin(radians)), c(std::cos(radians)) {}
};

// Quad::steps of every level: the sines and cosines of i cells (i = 0 .. 2n)
// of the level's cell, the same for every quad of the level and every frame
// (a thread keeps them: refine()).
class StepTables {
 public:
  const SinCos* of(int level, int32_t n);

 private:
  int32_t n_ = -1;
  std::vector<std::vector<SinCos>> by_level_;
};

// One selected quad as refinement sees it.
struct Quad {
  const SelectedQuad* selected = nullptr;
  int64_t ox = 0, oy = 0, scale = 1;  // in cells of the finest selected level
  geo::GeoBox bounds;
  double cell = 0;  // degrees per grid cell, along both axes
  // The grid's directions without a sine per point: its west and north
  // sides, and i cells (i = 0 .. 2n) of its level.
  SinCos west, north;
  const SinCos* steps = nullptr;
  // The prime vertical's radius of curvature at each grid row (its square
  // root and division were on the split criterion's critical path).
  std::vector<double> normals;
  double level_error = 0;
  std::shared_ptr<const DiamondErrors> errors;  // null: no data, height 0
  std::shared_ptr<const SideEdges> edges;       // null: no side takes coarser data
  // RefineOptions::criteria: a CriterionClass per slot (null: none).
  const uint8_t* criteria = nullptr;
  uint8_t blocking = 0;  // Side bits: shared with a coarser selected quad
  // Reusing decisions (RefineHistory).
  QuadDecisions* old = nullptr;  // the last record of this quad, if it still applies
  struct Block {
    DecisionBlock state;  // a reused block's, or a new one at this frame's view
    bool reused = false, budget_short = false;
    double moved = 0, turned = 0;           // since state.view
    double keep_below = 0, split_over = 0;  // the thresholds margins are checked for
  };
  std::vector<Block> blocks;
  std::vector<uint32_t> halves;  // recorded this frame
  bool all_reused = false;
  bool recording = true;
  uint32_t idle = 0;  // evaluations in a row that reused none of its blocks
};

// What pixels() computed, for the margins of its decision.
struct Criterion {
  double pixels = 0, metres = 0;
  bool quick = false;  // settled by the distance bound from the ball
  double near = 0;     // the ball's distance
  double far = 0;      // bounds the distance of the box's corners
  VerticalErrorParts parts;
};

struct Located {
  Located() = default;
  Located(int q, GridPoint at) : p(at), quad(q) {}
  // The point first: popped from a stack, it is then one aligned 8-byte
  // load (quad first, the compiler built it from two stores and a load
  // spanning both, which stalled store forwarding: a fifth of split()).
  GridPoint p;
  int quad = -1;
};

// Top-down refinement on several threads (refine_lanes.cpp): each quad is
// refined by one lane, which alone writes its marks and records; a split a
// lane forces across a side into another lane's quad goes to that lane's inbox.
struct Lanes {
  std::vector<uint8_t> owner;  // per quad: its lane
  struct Inbox {
    std::mutex mutex;
    std::vector<Located> splits;
    std::atomic<bool> any{false};  // a hint to look without locking
  };
  std::vector<std::unique_ptr<Inbox>> inboxes;  // per lane
};

class Refiner {
 public:
  Refiner(const View& view, TerrainModel& terrain, const Selection& selection,
          const RefineOptions& options, RefineCache::Impl& cache, SlotMarks& marks,
          StepTables& steps, std::span<Quad> quads)
      : view_(view),
        terrain_(terrain),
        selection_(selection),
        o_(options),
        cache_(cache),
        marks_(marks),
        steps_(steps),
        grid_(grid_of(terrain)),
        vertex_ids_(grid_.k()),
        quads_(quads),
        top_down_(options.variant == RefineVariant::kTopDown),
        history_(options.history ? &options.history->impl() : nullptr),
        corner_(view.tan_half_x * view.tan_half_x + view.tan_half_y * view.tan_half_y),
        quick_metres_(view.pixels_per_radian * (1 + corner_) / options.pixel_error),
        block_shift_(std::max(grid_.k() - 3, 0)),
        block_columns_((2 * grid_.n() >> block_shift_) + 1),
        block_rows_((grid_.n() >> block_shift_) + 1) {}

  // refine_prepare.cpp
  Status prepare();
  // The same view, threshold and selection as the last frame: its mesh.
  bool reuse_all() const { return reuse_all_; }

  // refine_criterion.cpp
  Status evaluate_criteria(CriterionEvaluator& evaluator,
                           std::vector<std::vector<uint8_t>>& classes);

  // refine_walk.cpp
  void top_down() {
    seed_top_down();
    run_generations();
  }
  void seed_top_down();
  void run_generations();
  void bottom_up();

  void run_lane();

  // refine_lanes.cpp
  Refiner lane(Lanes& lanes, uint32_t lane, MarkBlocks& blocks) const;
  void merge(const Refiner& lane);
  void count_unresolved();

  // refine_mesh.cpp
  RefinedMesh mesh(size_t expected);
  void emit_lane(std::vector<uint32_t>& out, std::vector<RefinedQuad>& quads);
  RefinedMesh gather(const Lanes& lanes, const std::vector<std::vector<uint32_t>>& indices,
                     const std::vector<RefinedQuad>& at) const;
  RefinedMesh reused_mesh() const;

  // refine_reuse.cpp
  void save_history(const RefinedMesh& mesh);

 private:
  int level(int q) const { return selection_.quads[static_cast<size_t>(q)].key.level; }

  // A recorded half of a decision: (x, y, over t) as in QuadDecisions::halves.
  static uint32_t pack(GridPoint p, bool over) {
    return static_cast<uint32_t>(p.x) | static_cast<uint32_t>(p.y) << 15 | uint32_t{over} << 31;
  }
  static GridPoint unpack(uint32_t e) {
    return {static_cast<int32_t>(e & 0x7fff), static_cast<int32_t>((e >> 15) & 0xffff)};
  }
  size_t block_of(GridPoint p) const {
    return static_cast<size_t>((p.y >> block_shift_) * block_columns_ + (p.x >> block_shift_));
  }

  // The mark of a diamond (MarkGrid::splittable, or a root), to write.
  uint8_t& mark(int q, GridPoint p) { return mark_at(q, grid_.slot(p)); }
  // (Inlined: called out of line, split() took half as long again.)
  [[gnu::always_inline]] uint8_t& mark_at(int q, uint32_t slot) {
    assert(mine(q));
    return marks_.at(q, slot, *blocks_);
  }
  uint8_t mark_of(int q, GridPoint p) const { return marks_.get(q, grid_.slot(p)); }

  // Whether this refiner decides quad q (always, but for a lane).
  [[gnu::always_inline]] bool mine(int q) const {
    return !lanes_ || lanes_->owner[static_cast<size_t>(q)] == lane_;
  }

  // The mark and error of a diamond about to be decided. (Here, so that it is
  // inlined into the loop of run_generations(): defined in another file, it
  // was a call per diamond.)
  void prefetch(const Located& l) const {
    const Diamond d = grid_.diamond(l.p);
    if (!MarkGrid::splittable(d)) return;
    const uint32_t slot = grid_.slot(l.p);
    marks_.prefetch(l.quad, slot);
    if (const DiamondErrors* e = quads_[static_cast<size_t>(l.quad)].errors.get()) {
      __builtin_prefetch(&e->at[slot]);
    }
  }

  // refine_prepare.cpp
  Status prepare(int index, const SelectedQuad& s, Quad& q);
  Result<TerrainModel::TilePtr> tile_of(const DataWindow& w);
  double height(const DataWindow& w, const TerrainModel::TilePtr& t, GridPoint p) const;
  Status prepare_edges(const SelectedQuad& s, Quad& q);

  // refine_walk.cpp
  void decide(int q, GridPoint p);
  bool mirror(int q, GridPoint p, Located& out);
  void split(int q, GridPoint p);
  bool blocked(int q, GridPoint p, const Diamond& d) const;
  void want_split_across(int q, GridPoint p, const Diamond& d);
  void send_splits();
  void take_splits();

  // refine_criterion.cpp
  double pixels(int q, GridPoint p, uint32_t slot, const Diamond& d, Criterion* out = nullptr,
                bool exact = false);

  // refine_margins.cpp
  void record(int q, GridPoint p, const Criterion& c, bool stuck);
  void keep_distance(Quad::Block& b, double distance, double metres);
  void margin(Quad::Block& b, const VerticalErrorParts& e, double metres, double far);

  // refine_reuse.cpp
  geo::TileKey neighbour_key(const SelectedQuad& s, size_t k) const;
  bool same_inputs(const QuadDecisions& r, size_t i) const;
  void match_history();
  void apply_history();

  // refine_mesh.cpp
  void emit_quad(int q, std::vector<uint32_t>& out);
  void emit(int q, GridPoint r, GridPoint a, GridPoint b, std::vector<uint32_t>& out);

  const View& view_;
  TerrainModel& terrain_;
  const Selection& selection_;
  const RefineOptions& o_;
  RefineCache::Impl& cache_;
  SlotMarks& marks_;
  StepTables& steps_;
  MarkGrid grid_;
  GridVertexIds vertex_ids_;  // of the triangles emitted
  int deepest_ = 0;
  int64_t globe_width_ = 0;
  std::span<Quad> quads_;  // one per selected quad, shared by the lanes
  bool top_down_;
  std::vector<Located> stack_, work_, generation_;
  RefineStats stats_;
  RefineHistory::Impl* history_;
  double corner_;  // tan^2 of the screen's corner
  // Metres of distance per metre of error at which the distance bound
  // reaches the threshold: K (1 + corner) / t.
  double quick_metres_;
  bool reuse_all_ = false;
  Criterion own_, across_;  // decide()'s
  // Lanes (null: one refiner for every quad).
  Lanes* lanes_ = nullptr;
  uint32_t lane_ = 0;
  MarkBlocks* blocks_ = &marks_.blocks();     // the lane's, or the marks' own
  std::vector<std::vector<Located>> outbox_;  // per lane: splits to send
  std::vector<Located> received_;
  std::vector<uint64_t> unresolved_keys_;  // quad << 32 | packed point
  int block_shift_ = 0;                    // blocks of 2^block_shift_ x 2^block_shift_ cells
  int32_t block_columns_ = 0, block_rows_ = 0;
};

// refine_lanes.cpp: a top-down refinement on the threads of `o.executor`.
size_t lane_count(const RefineOptions& o, const Selection& selection);
void remember_work(const Selection& selection, const RefinedMesh& mesh);
RefinedMesh refine_in_lanes(Refiner& r, const Selection& selection, size_t count,
                            Executor& executor, double& cpu_seconds);
double thread_cpu_seconds();

}  // namespace refinement
}  // namespace relief::lod
