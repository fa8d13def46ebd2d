#include "relief/lod/refine.h"

#include <algorithm>
#include <atomic>
#include <bit>
#include <cassert>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <ctime>
#include <list>
#include <mutex>
#include <optional>
#include <span>
#include <thread>
#include <unordered_map>

#include <fmt/format.h>

#include "angle_bound_range.h"
#include "diamond_errors.h"
#include "edge_marks.h"
#include "mark_blocks.h"
#include "quad_map.h"
#include "relief/geo/ellipsoid.h"
#include "relief/lod/criterion_evaluator.h"
#include "relief/lod/screen_error.h"

namespace relief::lod {

namespace {

// Range maxima over the heights by which the vertices of one side move when
// they take the coarser neighbour's data (a sparse table).
class SideMax {
 public:
  void build(const std::vector<float>& values) {
    table_.assign(1, values);
    for (size_t w = 1; 2 * w <= values.size(); w *= 2) {
      const std::vector<float>& prev = table_.back();
      std::vector<float> next(values.size() - 2 * w + 1);
      for (size_t i = 0; i < next.size(); ++i) next[i] = std::max(prev[i], prev[i + w]);
      table_.push_back(std::move(next));
    }
  }
  bool empty() const { return table_.empty(); }
  const std::vector<float>& values() const {
    static const std::vector<float> none;
    return table_.empty() ? none : table_[0];
  }
  // Largest value in [a, b], clamped to the side.
  float max(int32_t a, int32_t b) const {
    const int32_t last = static_cast<int32_t>(table_[0].size()) - 1;
    a = std::max(a, 0);
    b = std::min(b, last);
    if (a > b) return 0;
    const int level = std::bit_width(static_cast<uint32_t>(b - a + 1)) - 1;
    const auto& row = table_[static_cast<size_t>(level)];
    return std::max(row[static_cast<size_t>(a)], row[static_cast<size_t>(b - (1 << level) + 1)]);
  }

 private:
  std::vector<std::vector<float>> table_;
};

// How far the vertices of a quad's sides move by taking the coarser
// neighbour's data, per side (west, east, north, south; empty where none
// do), and what they were computed from: the same for every frame that
// selects the quad with the same coarser sides and the same data.
struct SideEdges {
  std::array<SideMax, 4> side;
};

bool same_window(const DataWindow& a, const DataWindow& b) {
  return a.tile == b.tile && a.x0 == b.x0 && a.y0 == b.y0 && a.width == b.width &&
         a.height == b.height;
}

struct EdgeInputs {
  TilePtr own_tile, parent_tile;  // held: compared by address
  DataWindow own, parent;
  uint8_t coarse_sides = 0, coarse_corners = 0;

  bool operator==(const EdgeInputs& o) const {
    return own_tile == o.own_tile && parent_tile == o.parent_tile && same_window(own, o.own) &&
           same_window(parent, o.parent) && coarse_sides == o.coarse_sides &&
           coarse_corners == o.coarse_corners;
  }
};

}  // namespace

struct RefineCache::Impl {
  std::mutex mutex;  // the render thread and the loader's threads
  uint64_t budget = 0, bytes = 0;
  std::list<geo::TileKey> lru;  // most recent first
  uint64_t frame = 1;           // counts end_frame()
  struct Entry {
    std::shared_ptr<const DiamondErrors> errors;
    std::list<geo::TileKey>::iterator at;
    bool prepared = false;  // off the render thread, not used by a frame yet
    uint64_t used = 0;      // the frame that last used it, or in which it was made
  };
  std::unordered_map<geo::TileKey, Entry, geo::TileKeyHash> entries;
  // The side heights of the last frame's quads (Refiner::prepare_edges: a
  // few hundred bilinear heights and a range table per quad, a tenth of a
  // fast camera's refinement when made every frame), and this frame's.
  struct Edges {
    EdgeInputs inputs;
    std::shared_ptr<const SideEdges> edges;
  };
  std::unordered_map<geo::TileKey, Edges, geo::TileKeyHash> last_edges, edges;

  std::shared_ptr<const SideEdges> find_edges(const geo::TileKey& key, const EdgeInputs& in) {
    std::lock_guard lock(mutex);
    for (auto* map : {&edges, &last_edges}) {
      if (auto it = map->find(key); it != map->end() && it->second.inputs == in) {
        edges[key] = it->second;
        return it->second.edges;
      }
    }
    return nullptr;
  }
  void keep_edges(const geo::TileKey& key, const EdgeInputs& in,
                  std::shared_ptr<const SideEdges> e) {
    std::lock_guard lock(mutex);
    edges[key] = {in, std::move(e)};
  }
  // What the next frame may reuse: this frame's.
  // The errors of every tile the frame held count as used, not only the
  // refined quads' own: a parent tile a frame draws coarse sides with, or
  // one selection checked, would otherwise be forgotten and loaded again
  // frame after frame.
  void end_frame(const TerrainModel& terrain) {
    std::vector<geo::TileKey> evicted;
    {
      std::lock_guard lock(mutex);
      last_edges.swap(edges);
      edges.clear();
      terrain.for_each_held([&](const geo::TileKey& key) {
        if (auto it = entries.find(key); it != entries.end()) it->second.used = frame;
      });
      ++frame;
      evict_over_budget(evicted);
    }
    for (const geo::TileKey& k : evicted) terrain.provider().forget(k);
  }

  // Evicts least recently used errors over the budget, except level 0's (kept,
  // as the loader keeps its tiles) and those the last two frames used or
  // that were made since (mutex held). Evicting those made the render thread
  // measure them again (the loaders' tiles pushing out the view's); the
  // budget may be exceeded by them (a view's tiles, a few hundred at most).
  // The tiles whose errors were evicted are forgotten by the provider
  // (TileProvider::forget): a view that wants one again loads it again, and
  // the loader's threads prepare it, instead of the render thread measuring it.
  void evict_over_budget(std::vector<geo::TileKey>& evicted) {
    for (auto it = lru.end(); bytes > budget && it != lru.begin();) {
      --it;
      auto old = entries.find(*it);
      if (old->second.used + 1 >= frame || it->level == 0) continue;
      bytes -= old->second.errors->bytes();
      evicted.push_back(*it);
      entries.erase(old);
      it = lru.erase(it);
    }
  }

  bool contains(const geo::TileKey& key) {
    std::lock_guard lock(mutex);
    return entries.contains(key);
  }

  // Adds the errors of `key`. Nothing is evicted here but at the end of a
  // frame, on the render thread, once the tiles the frame held are marked
  // used: a loader's thread evicting in the middle of a frame could take the
  // errors of a tile that frame is about to refine.
  void put(const geo::TileKey& key, std::shared_ptr<const DiamondErrors> errors, bool prepared) {
    std::lock_guard lock(mutex);
    if (auto it = entries.find(key); it != entries.end()) {  // measured twice: the same errors
      lru.splice(lru.begin(), lru, it->second.at);
      it->second.used = frame;
      return;
    }
    bytes += errors->bytes();
    lru.push_front(key);
    entries[key] = {std::move(errors), lru.begin(), prepared, frame};
  }

  // The errors of the diamonds of data tile `key`, counted in `stats` when
  // a frame uses them for the first time.
  Result<std::shared_ptr<const DiamondErrors>> get(TerrainModel& terrain, const MarkGrid& grid,
                                                   const geo::TileKey& key, RefineStats& stats) {
    {
      std::lock_guard lock(mutex);
      if (auto it = entries.find(key); it != entries.end()) {
        lru.splice(lru.begin(), lru, it->second.at);
        stats.tiles_prepared += it->second.prepared;
        it->second.prepared = false;
        it->second.used = frame;
        return it->second.errors;
      }
    }
    const TerrainModel::TilePtr tile = RELIEF_TRY(terrain.tile(key));
    if (!tile) return std::shared_ptr<const DiamondErrors>{};
    auto errors =
        std::make_shared<const DiamondErrors>(measure_diamonds(grid, *tile, terrain.border()));
    ++stats.tiles_measured;
    put(key, errors, false);
    return errors;
  }
};

// The decisions of the last frames (Reusing decisions, below). A quad's grid
// is cut into blocks of 2^s x 2^s cells; each block has the view its margins
// are relative to (an id into RefineHistory::Impl::views), how far the eye
// may move and the view turn from there, and the thresholds they hold for.
struct DecisionBlock {
  uint64_t view = 0;
  double move = INFINITY, turn = INFINITY;  // metres and radians
  // The thresholds its decisions hold for: those kept stay under the
  // lowest, those split over the highest.
  double lowest = 0, highest = INFINITY;
  bool margins = true;  // every decision has them (else: the same view and threshold only)
  bool later = false;   // has decisions made at a later view (so not the same view's only)
  double budget = 1;    // scale of the motion checked at its next evaluation
};

// One quad's: what its decisions depend on besides the view, its blocks, and
// the halves of diamonds it recorded: (x, y, over t) packed as x | y << 15 |
// over << 31. Recorded: the halves whose criterion is over t and which split
// (not stuck), and those under t off the quad's sides. Not recorded (decided
// afresh whenever reached): halves on the sides under t (the other half may
// change) and stuck ones over t (their unresolved statistics).
struct QuadDecisions {
  geo::TileKey key;
  std::array<geo::TileKey, 8> neighbours{};  // level -1: none
  uint8_t finer_sides = 0, coarse_sides = 0, coarse_corners = 0;
  uint8_t parent_data_sides = 0, parent_data_corners = 0;
  double level_error = 0;
  std::shared_ptr<const DiamondErrors> errors;  // held: compared by address
  std::shared_ptr<const SideEdges> edges;
  std::vector<DecisionBlock> blocks;
  std::vector<uint32_t> halves;
  // Frames in a row in which none of its blocks was reused: from kIdle on,
  // its decisions are recorded only every kProbe frames (recording costs
  // ~15 % of refinement; a fast camera leaves nothing to reuse).
  uint32_t idle = 0;
};

struct RefineHistory::Impl {
  // What every record depends on.
  const TerrainModel* terrain = nullptr;
  double pixels_per_radian = 0, tan_half_x = 0, tan_half_y = 0;
  // The views of the last frames, ids first_view.. (older blocks are not reused).
  struct ViewAt {
    Vec3 eye, right, up, forward;
    double pixel_error = 0;
  };
  std::vector<ViewAt> views;
  uint64_t first_view = 0;
  uint64_t frame = 0;
  std::vector<QuadDecisions> records;
  QuadMap<uint32_t> index{256};
  // The last frame's mesh and what it left unresolved, for a frame of the
  // same view and selection.
  std::vector<geo::TileKey> keys;
  std::vector<uint32_t> indices;
  std::vector<RefinedQuad> quads;
  uint64_t unresolved = 0;
  double max_unresolved_pixels = 0;
  std::vector<geo::TileKey> split_wanted;
  // A fast camera reuses few decisions and recording them costs more than
  // they save (a fifth of a refinement at 8 px on bench/view's Pyrenees
  // flight, reusing 19 %): after frames that reused under kMinReused of
  // their criteria (judge_reuse), the next `dormant` frames neither reuse
  // nor record; then one frame records and the next is judged again. Each
  // spell that ends in another low frame makes the next one twice as long
  // (`spell`, up to kMaxDormantFrames): a camera that keeps flying paid a
  // recording frame (+45 %) and a judged one (+30 %) every 16 frames, among
  // the slowest of a flight. A frame that reuses enough, or a camera that
  // stops, brings the spell back to kDormantFrames.
  uint32_t dormant = 0;
  uint32_t spell = 0;   // the next dormant spell's length (0: kDormantFrames)
  bool judged = false;  // the next frame's reuse is judged (it follows a recording frame)
  uint32_t low = 0;     // judged frames in a row under kMinReused
  bool woke = false;    // no frame reused enough since the last dormant spell
  // The last frame's view: a camera that stops wakes a dormant history at
  // once (its next frame reuses every decision) instead of after the spell.
  struct Seen {
    Vec3 eye, right, up, forward;
    double pixel_error = 0;
    bool operator==(const Seen& o) const {
      const auto eq = [](const Vec3& a, const Vec3& b) {
        return a.x == b.x && a.y == b.y && a.z == b.z;
      };
      return eq(eye, o.eye) && eq(right, o.right) && eq(up, o.up) && eq(forward, o.forward) &&
             pixel_error == o.pixel_error;
    }
  };
  std::optional<Seen> seen;
};

RefineHistory::RefineHistory() : impl_(std::make_unique<Impl>()) {}
RefineHistory::~RefineHistory() = default;
void RefineHistory::clear() {
  impl_ = std::make_unique<Impl>();
}

namespace {

// The grid of every quad of a store (its tiles' width: 2n cells of half a sample).
MarkGrid grid_of(const TerrainModel& terrain) {
  return MarkGrid(std::countr_zero(static_cast<uint32_t>(terrain.tile_width())));
}

}  // namespace

RefineCache::RefineCache(uint64_t budget_bytes) : impl_(std::make_shared<Impl>()) {
  impl_->budget = budget_bytes;
}
RefineCache::~RefineCache() = default;
uint64_t RefineCache::bytes() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->bytes;
}
size_t RefineCache::tiles() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->entries.size();
}

void RefineCache::prepare_on_load(TerrainModel& terrain) {
  if (terrain.blocking() || !terrain.store()) return;
  const MarkGrid grid = grid_of(terrain);
  const int border = terrain.border(), data_max = terrain.data_max_level();
  // The hook runs on the loader's threads and may outlive this cache: it
  // holds a weak pointer and does nothing once the cache is gone.
  terrain.add_prepare([cache = std::weak_ptr<Impl>(impl_), grid, border, data_max](
                          const geo::TileKey& key, const tiles::Raster& tile) {
    if (key.level > data_max) return;
    const std::shared_ptr<Impl> impl = cache.lock();
    if (!impl || impl->contains(key)) return;
    impl->put(key, std::make_shared<const DiamondErrors>(measure_diamonds(grid, tile, border)),
              true);
  });
  // Tiles resident before the hook (the loader reads level 0 at creation).
  for (const tiles::IndexEntry& e : terrain.store()->index(0).entries()) {
    if (impl_->contains(e.key) || !terrain.available(e.key)) continue;
    auto tile = terrain.tile(e.key);
    if (!tile || !*tile) continue;  // refine() will say what is wrong
    impl_->put(e.key, std::make_shared<const DiamondErrors>(measure_diamonds(grid, **tile, border)),
               true);
  }
}

namespace {

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
// Reusing decisions: the motion a recording quad's margins are checked for,
// per unit of its budget (adapted per quad between kMinBudget and kMaxBudget):
// the eye moving this share of a box's depth, the view turning this angle.
// and the threshold changing by this share (when it changed since the last frame).
constexpr double kMoveShare = 0.01, kTurn = 0.004, kBand = 0.03;
constexpr double kMinBudget = 1.0 / 16, kMaxBudget = 4;
// Views kept: a block decided longer ago is decided again.
constexpr size_t kViews = 64;
constexpr uint32_t kIdle = 2, kProbe = 4;
// Lanes of a parallel top-down refinement (Lanes::owner is a byte).
constexpr size_t kMaxLanes = 64;
// Top-down: diamonds decided ahead of the one whose data is fetched.
constexpr size_t kAhead = 8;
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
  const SinCos* of(int level, int32_t n) {
    if (n != n_) {
      by_level_.clear();
      n_ = n;
    }
    if (by_level_.size() <= static_cast<size_t>(level)) by_level_.resize(level + 1);
    std::vector<SinCos>& steps = by_level_[static_cast<size_t>(level)];
    if (steps.empty()) {
      const double cell = geo::TileKey{level, 0, 0}.bounds().height() / n;
      steps.reserve(static_cast<size_t>(2 * n + 1));
      for (int32_t i = 0; i <= 2 * n; ++i) steps.emplace_back(i * cell * kDegree);
    }
    return steps.data();
  }

 private:
  int32_t n_ = -1;
  std::vector<std::vector<SinCos>> by_level_;
};

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

// Top-down refinement on several threads ("Lanes", below): each quad is
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

  Status prepare() {
    int deepest = 0;
    bool linked = selection_.quads.size() <= 1;
    for (const SelectedQuad& q : selection_.quads) {
      if (q.key.level > terrain_.data_max_level()) {
        return fail(fmt::format(
            "refine: quad {} is deeper than the store's finest level {}; cap the selection there",
            q.key.to_string(), terrain_.data_max_level()));
      }
      deepest = std::max(deepest, q.key.level);
      for (int32_t n : q.neighbours) linked |= n >= 0;
    }
    if (!linked) {
      return fail(
          "refine: the selection has no neighbour indices (SelectionOptions::neighbour_indices)");
    }
    deepest_ = deepest;
    globe_width_ = int64_t{2} * grid_.n() << deepest;
    assert(quads_.size() == selection_.quads.size());
    marks_.reset(grid_, quads_.size());
    for (size_t i = 0; i < quads_.size(); ++i)
      RELIEF_CHECK(prepare(static_cast<int>(i), selection_.quads[i], quads_[i]));
    if (history_) match_history();
    if (reuse_all_) return {};
    // A side shared with finer quads is split at its midpoint (their corner).
    for (size_t i = 0; i < quads_.size(); ++i) {
      const uint8_t finer = selection_.quads[i].finer_sides;
      const int32_t n = grid_.n();
      const int q = static_cast<int>(i);
      if (finer & kWest) split(q, {0, n / 2});
      if (finer & kEast) split(q, {2 * n, n / 2});
      for (int32_t x : {n / 2, 3 * n / 2}) {
        if (finer & kNorth) split(q, {x, 0});
        if (finer & kSouth) split(q, {x, n});
      }
    }
    if (history_) apply_history();
    return {};
  }

  // The same view, threshold and selection as the last frame: its mesh.
  bool reuse_all() const { return reuse_all_; }

  void top_down() {
    seed_top_down();
    run_generations();
  }

  // The first diamonds of every quad (their children come by splits).
  void seed_top_down() {
    const int32_t n = grid_.n();
    for (size_t i = 0; i < quads_.size(); ++i) {
      for (const GridPoint p : {GridPoint{n / 2, 0}, GridPoint{3 * n / 2, 0}, GridPoint{n / 2, n},
                                GridPoint{3 * n / 2, n}, GridPoint{0, n / 2}, GridPoint{n, n / 2},
                                GridPoint{2 * n, n / 2}}) {
        work_.push_back({static_cast<int>(i), p});
      }
    }
  }

  void run_generations() {
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

  // Lanes: a copy of this refiner (after prepare() and seed_top_down()) that
  // refines the quads `lanes` gives lane `lane`, with its own mark blocks,
  // starting from their seeds.
  Refiner lane(Lanes& lanes, uint32_t lane, MarkBlocks& blocks) const {
    Refiner r = *this;
    r.lanes_ = &lanes;
    r.lane_ = lane;
    r.blocks_ = &blocks;
    r.stats_ = {};
    r.work_.clear();
    for (const Located& l : work_) {
      if (r.mine(l.quad)) r.work_.push_back(l);
    }
    r.outbox_.assign(lanes.inboxes.size(), {});
    return r;
  }

  // One round of a lane: what its inbox holds and what that splits, until
  // neither its inbox nor its work has more. Splits sent to other lanes after
  // their round ended wait for the next round (refine() runs rounds until no
  // inbox has any): no lane waits for another, so the rounds finish whatever
  // the executor runs at once.
  void run_lane() {
    take_splits();
    run_generations();
    send_splits();
  }

  // This lane's statistics added to those of the refiner it was copied from.
  void merge(const Refiner& lane) {
    stats_.marks_evaluated += lane.stats_.marks_evaluated;
    stats_.marks_near += lane.stats_.marks_near;
    stats_.max_unresolved_pixels =
        std::max(stats_.max_unresolved_pixels, lane.stats_.max_unresolved_pixels);
    unresolved_keys_.insert(unresolved_keys_.end(), lane.unresolved_keys_.begin(),
                            lane.unresolved_keys_.end());
    for (const geo::TileKey& k : lane.stats_.split_wanted) {
      auto& wanted = stats_.split_wanted;
      if (std::find(wanted.begin(), wanted.end(), k) == wanted.end()) wanted.push_back(k);
    }
  }

  // After the lanes merged: a diamond both lanes of a shared side found
  // stuck is counted once, as by one refiner.
  void count_unresolved() {
    std::sort(unresolved_keys_.begin(), unresolved_keys_.end());
    stats_.unresolved += static_cast<uint64_t>(
        std::unique(unresolved_keys_.begin(), unresolved_keys_.end()) - unresolved_keys_.begin());
  }

  // RefineOptions::criteria: every diamond's criterion of every quad
  // evaluated by `evaluator` (into `classes`, which must outlive the
  // refinement), each quad's inputs as pixels() reads them.
  Status evaluate_criteria(CriterionEvaluator& evaluator,
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

  void bottom_up() {
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

  // `expected`: about as many indices as the last frame's (growing the
  // buffer took a few percent of a frame in copies and page faults).
  RefinedMesh mesh(size_t expected) {
    RefinedMesh out;
    out.indices.reserve(expected + expected / 8);
    out.grid_k = grid_.k();
    out.quads.resize(quads_.size());
    for (size_t i = 0; i < quads_.size(); ++i) {
      out.quads[i].first_index = static_cast<uint32_t>(out.indices.size());
      emit_quad(static_cast<int>(i), out.indices);
      out.quads[i].index_count =
          static_cast<uint32_t>(out.indices.size()) - out.quads[i].first_index;
    }
    out.stats = stats_;
    return out;
  }

  // The triangles of quad q's marks.
  void emit_quad(int q, std::vector<uint32_t>& out) {
    const int32_t n = grid_.n();
    for (int32_t h = 0; h < 2; ++h) {
      const GridPoint c{h * n + n / 2, n / 2};
      const GridPoint nw{h * n, 0}, ne{h * n + n, 0}, se{h * n + n, n}, sw{h * n, n};
      const std::pair<GridPoint, GridPoint> sides[] = {{nw, ne}, {ne, se}, {se, sw}, {sw, nw}};
      for (const auto& [a, b] : sides) emit(q, c, a, b, out);
    }
  }

  // Lanes: the triangles of this lane's quads into `out`, each quad's
  // (RefinedQuad relative to `out`) in `quads`.
  void emit_lane(std::vector<uint32_t>& out, std::vector<RefinedQuad>& quads) {
    out.clear();
    for (size_t i = 0; i < quads_.size(); ++i) {
      if (!mine(static_cast<int>(i))) continue;
      quads[i].first_index = static_cast<uint32_t>(out.size());
      emit_quad(static_cast<int>(i), out);
      quads[i].index_count = static_cast<uint32_t>(out.size()) - quads[i].first_index;
    }
  }

  // Lanes: the mesh of the triangles emit_lane() made, in quad order.
  RefinedMesh gather(const Lanes& lanes, const std::vector<std::vector<uint32_t>>& indices,
                     const std::vector<RefinedQuad>& at) const {
    RefinedMesh out;
    size_t total = 0;
    for (const RefinedQuad& q : at) total += q.index_count;
    out.indices.resize(total);
    out.grid_k = grid_.k();
    out.quads.resize(quads_.size());
    uint32_t next = 0;
    for (size_t i = 0; i < quads_.size(); ++i) {
      const std::vector<uint32_t>& from = indices[lanes.owner[i]];
      std::copy_n(from.begin() + at[i].first_index, at[i].index_count, out.indices.begin() + next);
      out.quads[i] = {next, at[i].index_count};
      next += at[i].index_count;
    }
    out.stats = stats_;
    return out;
  }

  RefinedMesh reused_mesh() const {
    RefinedMesh out;
    out.grid_k = grid_.k();
    out.indices = history_->indices;
    out.quads = history_->quads;
    out.stats = stats_;
    out.stats.unresolved = history_->unresolved;
    out.stats.max_unresolved_pixels = history_->max_unresolved_pixels;
    out.stats.split_wanted = history_->split_wanted;
    return out;
  }

  // This frame's records replace the last ones.
  void save_history(const RefinedMesh& mesh) {
    if (!history_) return;
    RefineHistory::Impl& h = *history_;
    std::vector<QuadDecisions> records(quads_.size());
    QuadMap<uint32_t> index(quads_.size());
    std::vector<geo::TileKey> keys(quads_.size());
    for (size_t i = 0; i < quads_.size(); ++i) {
      Quad& q = quads_[i];
      const SelectedQuad& s = selection_.quads[i];
      QuadDecisions& r = records[i];
      keys[i] = s.key;
      index.set(s.key, static_cast<uint32_t>(i));
      if (reuse_all_) {
        r = std::move(*q.old);
        continue;
      }
      r.key = s.key;
      for (size_t k = 0; k < 8; ++k) r.neighbours[k] = neighbour_key(s, k);
      r.finer_sides = s.finer_sides;
      r.coarse_sides = s.coarse_sides;
      r.coarse_corners = s.coarse_corners;
      r.parent_data_sides = s.parent_data_sides;
      r.parent_data_corners = s.parent_data_corners;
      r.level_error = q.level_error;
      r.errors = q.errors;
      r.edges = q.edges;
      r.idle = q.idle;
      r.blocks.resize(q.blocks.size());
      for (size_t b = 0; b < q.blocks.size(); ++b) {
        Quad::Block& qb = q.blocks[b];
        DecisionBlock& d = r.blocks[b];
        d = qb.state;
        if (qb.reused) continue;
        if (!q.recording) {  // nothing recorded: decided afresh next time
          d.margins = d.later = false;
          continue;
        }
        // Margins too short for the motion checked: a smaller one next time;
        // margins that held until the view went beyond them: a larger one.
        const DecisionBlock* before =
            q.old && q.old->blocks.size() == q.blocks.size() ? &q.old->blocks[b] : nullptr;
        d.budget = qb.budget_short             ? std::max(d.budget / 2, kMinBudget)
                   : before && before->margins ? std::min(d.budget * 2, kMaxBudget)
                                               : d.budget;
      }
      if (q.old && !q.blocks.empty()) {  // the reused blocks' halves, then this frame's
        for (const uint32_t e : q.old->halves) {
          if (q.blocks[block_of(unpack(e))].reused) r.halves.push_back(e);
        }
      }
      r.halves.insert(r.halves.end(), q.halves.begin(), q.halves.end());
    }
    h.records = std::move(records);
    h.index = std::move(index);
    h.keys = std::move(keys);
    if (!reuse_all_) {
      h.indices = mesh.indices;
      h.quads = mesh.quads;
      h.unresolved = mesh.stats.unresolved;
      h.max_unresolved_pixels = mesh.stats.max_unresolved_pixels;
      h.split_wanted = mesh.stats.split_wanted;
    }
  }

 private:
  int level(int q) const { return selection_.quads[static_cast<size_t>(q)].key.level; }

  static uint32_t pack(GridPoint p, bool over) {
    return static_cast<uint32_t>(p.x) | static_cast<uint32_t>(p.y) << 15 | uint32_t{over} << 31;
  }
  static GridPoint unpack(uint32_t e) {
    return {static_cast<int32_t>(e & 0x7fff), static_cast<int32_t>((e >> 15) & 0xffff)};
  }
  size_t block_of(GridPoint p) const {
    return static_cast<size_t>((p.y >> block_shift_) * block_columns_ + (p.x >> block_shift_));
  }

  geo::TileKey neighbour_key(const SelectedQuad& s, size_t k) const {
    const int32_t j = s.neighbours[k];
    return j >= 0 ? selection_.quads[static_cast<size_t>(j)].key : geo::TileKey{-1, 0, 0};
  }

  // Whether the record was made for the quad as selected now: the same
  // neighbours (so the same marks mirror, block and split across), the same
  // data (errors by address: the record holds them) and side heights.
  bool same_inputs(const QuadDecisions& r, size_t i) const {
    const SelectedQuad& s = selection_.quads[i];
    const Quad& q = quads_[i];
    for (size_t k = 0; k < 8; ++k) {
      if (!(r.neighbours[k] == neighbour_key(s, k))) return false;
    }
    if (r.finer_sides != s.finer_sides || r.coarse_sides != s.coarse_sides ||
        r.coarse_corners != s.coarse_corners || r.parent_data_sides != s.parent_data_sides ||
        r.parent_data_corners != s.parent_data_corners || r.level_error != q.level_error ||
        r.errors != q.errors) {
      return false;
    }
    if (r.edges == q.edges) return true;
    if (!r.edges || !q.edges) return false;
    for (size_t k = 0; k < 4; ++k) {
      if (r.edges->side[k].values() != q.edges->side[k].values()) return false;
    }
    return true;
  }

  static bool same(const Vec3& a, const Vec3& b) { return a.x == b.x && a.y == b.y && a.z == b.z; }

  // Which blocks reuse their decisions: those of quads with the same inputs,
  // within their margins of the motion since their view (how far the eye
  // moved, and the angle the view turned: the basis change is a rotation by
  // w with |right' - right|^2 + |up' - up|^2 + |forward' - forward|^2 =
  // 8 sin^2(w / 2)), or at the same view and threshold.
  void match_history() {
    RefineHistory::Impl& h = *history_;
    if (h.terrain != &terrain_ || h.pixels_per_radian != view_.pixels_per_radian ||
        h.tan_half_x != view_.tan_half_x || h.tan_half_y != view_.tan_half_y) {
      h = RefineHistory::Impl{};
      h.terrain = &terrain_;
      h.pixels_per_radian = view_.pixels_per_radian;
      h.tan_half_x = view_.tan_half_x;
      h.tan_half_y = view_.tan_half_y;
    }
    // A threshold that changes from frame to frame (speed-dependent level of
    // detail): margins are also checked for a band of thresholds around it.
    const bool steady = !h.views.empty() && h.views.back().pixel_error == o_.pixel_error;
    struct Motion {
      double moved, turned;
      bool same;
    };
    std::vector<Motion> motions;
    for (const RefineHistory::Impl::ViewAt& v : h.views) {
      const Vec3 dr = view_.right - v.right, du = view_.up - v.up, df = view_.forward - v.forward;
      const double sine = std::sqrt((dot(dr, dr) + dot(du, du) + dot(df, df)) / 8);
      motions.push_back(
          {length(view_.eye - v.eye), 2 * std::asin(std::min(1.0, sine)) + kAngleSlack,
           same(view_.eye, v.eye) && same(view_.right, v.right) && same(view_.up, v.up) &&
               same(view_.forward, v.forward) && v.pixel_error == o_.pixel_error});
    }
    const bool still = !motions.empty() && motions.back().same;
    if (h.views.size() == kViews) {
      h.views.erase(h.views.begin());
      motions.erase(motions.begin());
      ++h.first_view;
    }
    const uint64_t now = h.first_view + h.views.size();
    h.views.push_back({view_.eye, view_.right, view_.up, view_.forward, o_.pixel_error});
    bool all = still && h.keys.size() == quads_.size();
    const size_t blocks = static_cast<size_t>(block_columns_) * block_rows_;
    for (size_t i = 0; i < quads_.size(); ++i) {
      Quad& q = quads_[i];
      const uint32_t* at = h.index.find(selection_.quads[i].key);
      QuadDecisions* r = at ? &h.records[*at] : nullptr;
      if (r && same_inputs(*r, i)) q.old = r;
      all = all && q.old && h.keys[i] == selection_.quads[i].key;
      auto fresh = [&](Quad::Block& qb, size_t b) {
        qb.state.view = now;
        if (r && r->blocks.size() == blocks) qb.state.budget = r->blocks[b].budget;
        const double band = steady ? 0.0 : kBand * qb.state.budget;
        qb.keep_below = o_.pixel_error * (1 - band);
        qb.split_over = o_.pixel_error * (1 + band);
      };
      bool any = false;
      q.all_reused = q.old && q.old->blocks.size() == blocks;
      if (q.all_reused) {
        q.blocks.resize(blocks);
        for (size_t b = 0; b < blocks; ++b) {
          Quad::Block& qb = q.blocks[b];
          fresh(qb, b);
          const DecisionBlock& d = q.old->blocks[b];
          const Motion* m = d.view >= h.first_view && d.view < now
                                ? &motions[static_cast<size_t>(d.view - h.first_view)]
                                : nullptr;
          qb.reused = m && ((m->same && !d.later) ||
                            (d.margins && m->moved <= d.move && m->turned <= d.turn &&
                             d.lowest <= o_.pixel_error && o_.pixel_error <= d.highest));
          q.all_reused = q.all_reused && qb.reused;
          any = any || qb.reused;
          if (!qb.reused) continue;
          qb.state = d;
          qb.moved = m->moved;
          qb.turned = m->turned;
        }
      }
      stats_.quads_reused += q.all_reused;
      q.idle = any ? 0 : r ? r->idle + 1 : 0;
      q.recording = any || q.idle < kIdle || h.frame % kProbe == 0;
      if (q.recording && q.blocks.empty()) {
        q.blocks.resize(blocks);
        for (size_t b = 0; b < blocks; ++b) fresh(q.blocks[b], b);
      }
    }
    ++h.frame;
    reuse_all_ = all;
    if (reuse_all_) {
      for (const Quad& q : quads_) stats_.marks_reused += q.old->halves.size();
    }
  }

  // The recorded decisions of the reused blocks: splits made, kept marks
  // marked kept (decide() passes them).
  void apply_history() {
    for (size_t i = 0; i < quads_.size(); ++i) {
      const Quad& q = quads_[i];
      if (!q.old || q.blocks.empty()) continue;
      for (const uint32_t e : q.old->halves) {
        const GridPoint p = unpack(e);
        if (!q.blocks[block_of(p)].reused) continue;
        ++stats_.marks_reused;
        if (e >> 31) {
          split(static_cast<int>(i), p);
        } else if (uint8_t& m = mark(static_cast<int>(i), p); m == kUnknown) {
          m = kKept;
        }
      }
    }
  }

  // The mark of a diamond (MarkGrid::splittable, or a root), to write.
  uint8_t& mark(int q, GridPoint p) { return mark_at(q, grid_.slot(p)); }
  // (Inlined: called out of line, split() took half as long again.)
  [[gnu::always_inline]] uint8_t& mark_at(int q, uint32_t slot) {
    assert(mine(q));
    return marks_.at(q, slot, *blocks_);
  }

  // Whether this refiner decides quad q (always, but for a lane).
  [[gnu::always_inline]] bool mine(int q) const {
    return !lanes_ || lanes_->owner[static_cast<size_t>(q)] == lane_;
  }

  // Lanes: the splits forced into other lanes' quads, to their inboxes.
  void send_splits() {
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
  void take_splits() {
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
  uint8_t mark_of(int q, GridPoint p) const { return marks_.get(q, grid_.slot(p)); }

  Status prepare(int index, const SelectedQuad& s, Quad& q) {
    const int32_t n = grid_.n();
    q.selected = &s;
    q.scale = int64_t{1} << (deepest_ - s.key.level);
    q.ox = int64_t{s.key.x} * 2 * n * q.scale;
    q.oy = int64_t{s.key.y} * n * q.scale;
    q.bounds = s.key.bounds();
    q.cell = q.bounds.height() / n;
    q.west = SinCos(q.bounds.west * kDegree);
    q.north = SinCos(q.bounds.north * kDegree);
    q.steps = steps_.of(s.key.level, n);
    q.normals.resize(static_cast<size_t>(n) + 1);
    for (int32_t y = 0; y <= n; ++y) {
      const SinCos& step = q.steps[y];
      const double sin_lat = q.north.s * step.c - q.north.c * step.s;
      q.normals[static_cast<size_t>(y)] = geo::wgs84::prime_vertical_radius(sin_lat);
    }
    q.level_error = RELIEF_TRY(terrain_.level_error(s.key));
    if (q.level_error > 0) {
      // No split makes up for the distance between the level's full mesh
      // and the finest data: a quad where that alone may exceed the threshold
      // refines to its full mesh, and the selection should split it instead.
      TerrainModel::QuadInfo* info = RELIEF_TRY(terrain_.quad(s.key));
      if (vertical_error_pixels(view_, info->box, q.bounds, q.level_error) > o_.pixel_error) {
        ++stats_.too_coarse;
        stats_.split_wanted.push_back(s.key);
        // A frame whose selection waits for data (never complete) keeps
        // such quads while their children's tiles load, often many at once
        // after a turn: their full meshes (up to 2 x 512 x 256 triangles
        // each) bought no bound and took 2 M triangles and a second a frame
        // on llvmpipe. They are refined against their own data instead.
        if (!terrain_.blocking() && selection_.stats.waiting > 0) q.level_error = 0;
      }
    }
    for (int side = 0; side < 4; ++side) {
      if ((s.coarse_sides & kSideBits[side]) && s.neighbours[static_cast<size_t>(2 * side)] >= 0) {
        q.blocking |= kSideBits[side];
      }
    }
    if (const DataWindow w = terrain_.window(s.key); w.tile) {
      q.errors = RELIEF_TRY(cache_.get(terrain_, grid_, *w.tile, stats_));
    }
    // The halves' centres (their corners are vertices: no marks).
    mark(index, {n / 2, n / 2}) = mark(index, {3 * n / 2, n / 2}) = kSplit;
    return prepare_edges(s, q);
  }

  // The tile of a data window (null without data).
  Result<TerrainModel::TilePtr> tile_of(const DataWindow& w) {
    if (!w.tile) return TerrainModel::TilePtr{};
    return terrain_.tile(*w.tile);
  }

  // Height of grid point p from a data window and its tile (0 without data).
  double height(const DataWindow& w, const TerrainModel::TilePtr& t, GridPoint p) const {
    if (!t) return 0.0;
    const double u = static_cast<double>(p.x) / (2 * grid_.n());
    const double v = static_cast<double>(p.y) / grid_.n();
    return TerrainModel::bilinear(*t, terrain_.border(), w.x0 + u * w.width, w.y0 + v * w.height);
  }

  // |parent - own| heights of the vertices on sides (and at corners) that take
  // the coarser neighbour's data, as range-maximum tables per side.
  // The last frame's when it had the same inputs (RefineCache::Impl::edges).
  Status prepare_edges(const SelectedQuad& s, Quad& q) {
    if (!s.coarse_sides && !s.coarse_corners) return {};
    const int32_t n = grid_.n();
    const DataWindow own = terrain_.window(s.key), parent = terrain_.parent_window(s.key);
    const TerrainModel::TilePtr own_tile = RELIEF_TRY(tile_of(own));
    const TerrainModel::TilePtr parent_tile = RELIEF_TRY(tile_of(parent));
    const EdgeInputs inputs{own_tile, parent_tile, own, parent, s.coarse_sides, s.coarse_corners};
    if ((q.edges = cache_.find_edges(s.key, inputs))) return {};
    auto at = [&](int side, int32_t t) {
      return side == 0   ? GridPoint{0, t}
             : side == 1 ? GridPoint{2 * n, t}
             : side == 2 ? GridPoint{t, 0}
                         : GridPoint{t, n};
    };
    std::array<std::vector<float>, 4> diff;
    auto moved = [&](GridPoint p) {
      const double d = height(parent, parent_tile, p) - height(own, own_tile, p);
      float f = static_cast<float>(std::abs(d));
      if (static_cast<double>(f) < std::abs(d)) f = std::nextafter(f, INFINITY);
      return f;
    };
    for (int side = 0; side < 4; ++side) {
      const int32_t length = side < 2 ? n : 2 * n;
      diff[side].assign(static_cast<size_t>(length) + 1, 0.0f);
      if (!(s.coarse_sides & kSideBits[side])) continue;
      for (int32_t t = 0; t <= length; t += 2) diff[side][t] = moved(at(side, t));
    }
    const struct {
      uint8_t corner;
      GridPoint p;
      int sides[2];
      int32_t t[2];
    } corners[] = {{kNorthWest, {0, 0}, {0, 2}, {0, 0}},
                   {kNorthEast, {2 * n, 0}, {1, 2}, {0, 2 * n}},
                   {kSouthWest, {0, n}, {0, 3}, {n, 0}},
                   {kSouthEast, {2 * n, n}, {1, 3}, {n, 2 * n}}};
    uint8_t used = s.coarse_sides;
    for (const auto& c : corners) {
      if (!(s.coarse_corners & c.corner)) continue;
      const float d = moved(c.p);
      for (int k = 0; k < 2; ++k) {
        diff[c.sides[k]][c.t[k]] = std::max(diff[c.sides[k]][c.t[k]], d);
        used |= kSideBits[c.sides[k]];
      }
    }
    auto edges = std::make_shared<SideEdges>();
    for (int side = 0; side < 4; ++side) {
      if (used & kSideBits[side]) edges->side[side].build(diff[side]);
    }
    q.edges = edges;
    cache_.keep_edges(s.key, inputs, std::move(edges));
    return {};
  }

  // The same edge mark in the quad across the border, if one is selected:
  // true and `out`. (Not an optional<Located>: returned in two registers,
  // the compiler assembled it on the stack from a 32-bit and an 8-bit store
  // and read it back in one 64-bit load, which stalled store forwarding.)
  bool mirror(int q, GridPoint p, Located& out) {
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
  void split(int q, GridPoint p) {
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
  bool blocked(int q, GridPoint p, const Diamond& d) const {
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
  void want_split_across(int q, GridPoint p, const Diamond& d) {
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

  // The split criterion's value for the part of diamond d inside quad q: the
  // screen bound of its error in a box around it and its descendants (nested
  // in its parents' boxes, so the value never grows from parent to child).
  //
  // Unless `exact`, the value returned is only on the same side of the
  // threshold as the criterion's (the mesh depends on nothing else): bounds
  // from the ball's centre settle most diamonds (angle_bound_range.h), the
  // exact bound the others. With `out`, only the distance bound's shortcut.
  double pixels(int q, GridPoint p, uint32_t slot, const Diamond& d, Criterion* out = nullptr,
                bool exact = false) {
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
    const double lon = quad.bounds.west + p.x * quad.cell,
                 lat = quad.bounds.north - p.y * quad.cell;
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

  // tan(kTurn * budget + kAngleSlack + asin(kMoveShare * budget)) for the
  // budgets 2^-4 .. 2^2.
  static double widening(double budget) {
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

  // Records one half of a decision (QuadDecisions says which) with its margins.
  void record(int q, GridPoint p, const Criterion& c, bool stuck) {
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
  void keep_distance(Quad::Block& b, double distance, double metres) {
    const double needed = view_.pixels_per_radian * metres * (1 + corner_) / b.keep_below;
    const double slack = distance * (1 - kSafety) - needed * (1 + kSafety) - kSlackMetres;
    allow(b, slack, INFINITY);
  }

  // A decision made now holds within `move` and `turn` of this view: within
  // move - moved and turn - turned of a reused block's (triangle inequality).
  static void allow(Quad::Block& b, double move, double turn) {
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

  // Otherwise, for an eye motion of at most move = kMoveShare * budget * z_min
  // and a turn of at most w = kTurn * budget: every corner's depth changes by
  // at most move + far * w (far: the largest distance of a corner), the
  // angle between a corner's direction and the view direction by at most
  // w + asin(move / z_min), that between the view direction and a normal by
  // at most w (so S and C by at most w), the box's distance by at most move.
  // The criterion's value stays on its side of t when the bound computed with
  // every term moved against it does.
  void margin(Quad::Block& b, const VerticalErrorParts& e, double metres, double far) {
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

  // The mark and error of a diamond about to be decided.
  void prefetch(const Located& l) const {
    const Diamond d = grid_.diamond(l.p);
    if (!MarkGrid::splittable(d)) return;
    const uint32_t slot = grid_.slot(l.p);
    marks_.prefetch(l.quad, slot);
    if (const DiamondErrors* e = quads_[static_cast<size_t>(l.quad)].errors.get()) {
      __builtin_prefetch(&e->at[slot]);
    }
  }

  // Evaluates the split criterion of an undecided mark (for both quads when
  // it lies on their shared side) and splits it or keeps it.
  void decide(int q, GridPoint p) {
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
      px = std::max(px,
                    pixels(other->quad, other->p, other_slot, od, recorded(other->quad, across)));
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

  // The triangle with right angle at r and hypotenuse (a, b), or its children.
  void emit(int q, GridPoint r, GridPoint a, GridPoint b, std::vector<uint32_t>& out) {
    const GridPoint m{(a.x + b.x) / 2, (a.y + b.y) / 2};
    // A hypotenuse of two cells along an axis is a sample's side: never split.
    const bool sample_side = std::abs(a.x - b.x) + std::abs(a.y - b.y) == 2;
    if (!sample_side && mark_of(q, m) == kSplit) {
      emit(q, m, a, r, out);
      emit(q, m, r, b, out);
      return;
    }
    // Counter-clockwise seen from above: in (x, -y), as MeshTopology.
    const int64_t area = int64_t{a.x - r.x} * (r.y - b.y) - int64_t{r.y - a.y} * (b.x - r.x);
    if (area < 0) std::swap(a, b);
    const auto id = [this](GridPoint g) {
      return vertex_ids_(static_cast<uint32_t>(g.x), static_cast<uint32_t>(g.y));
    };
    // One at a time: inserted from a list, the ids went through the stack as
    // 32-bit stores read back in a 64-bit load (a stalled store forwarding).
    const uint32_t ir = id(r), ia = id(a), ib = id(b);
    out.push_back(ir);
    out.push_back(ia);
    out.push_back(ib);
  }

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

}  // namespace

namespace {

// A history whose frames reused less than this share of their decisions
// kLowFrames times in a row (once, right after a dormant spell) goes dormant
// for kDormantFrames frames, then twice as many each time, up to
// kMaxDormantFrames (RefineHistory::Impl::dormant and spell).
constexpr double kMinReused = 0.25;
constexpr uint32_t kLowFrames = 3, kDormantFrames = 14, kMaxDormantFrames = 112;

void judge_reuse(RefineHistory::Impl& h, const RefineStats& s) {
  if (!h.judged) {  // the frame recorded: the next one is judged
    h.judged = true;
    return;
  }
  const uint64_t all = s.marks_evaluated + s.marks_reused;
  if (all == 0 || static_cast<double>(s.marks_reused) >= kMinReused * static_cast<double>(all)) {
    h.low = 0;
    h.woke = false;
    h.spell = 0;
    return;
  }
  if (++h.low >= (h.woke ? 1 : kLowFrames)) {
    h.dormant = h.spell > 0 ? h.spell : kDormantFrames;
    h.spell = std::min(2 * h.dormant, kMaxDormantFrames);
    h.low = 0;
    h.judged = false;
    h.woke = true;
  }
}

double thread_cpu_seconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + static_cast<double>(t.tv_nsec) * 1e-9;
}

// Lanes for a top-down refinement: one per thread of the executor, at most
// one per quad.
size_t lane_count(const RefineOptions& o, const Selection& selection) {
  if (!o.executor || o.variant != RefineVariant::kTopDown) return 1;
  return std::min<size_t>({o.executor->concurrency(), selection.quads.size(), kMaxLanes});
}

// A quad's work in the last frame that refined it on this thread with an
// executor: its triangles (about proportional to the criteria evaluated),
// for dealing the next frame's quads out to lanes.
thread_local std::unordered_map<geo::TileKey, uint32_t, geo::TileKeyHash> last_work;

void remember_work(const Selection& selection, const RefinedMesh& mesh) {
  last_work.clear();
  for (size_t i = 0; i < selection.quads.size(); ++i) {
    last_work[selection.quads[i].key] = mesh.quads[i].index_count / 3;
  }
}

// Deals the quads out to `count` lanes, heaviest first to the lane with the
// least work so far (by the last frame's work; a quad new to the view counts
// as the mean), so that the lanes end together.
std::vector<uint8_t> deal(const Selection& selection, size_t count) {
  const size_t n = selection.quads.size();
  std::vector<double> work(n, -1);
  double known = 0;
  size_t found = 0;
  for (size_t i = 0; i < n; ++i) {
    if (auto it = last_work.find(selection.quads[i].key); it != last_work.end()) {
      work[i] = it->second + 1.0;
      known += work[i];
      ++found;
    }
  }
  const double mean = found ? known / static_cast<double>(found) : 1.0;
  std::vector<uint32_t> order(n);
  for (size_t i = 0; i < n; ++i) {
    if (work[i] < 0) work[i] = mean;
    order[i] = static_cast<uint32_t>(i);
  }
  std::stable_sort(order.begin(), order.end(),
                   [&](uint32_t a, uint32_t b) { return work[a] > work[b]; });
  std::vector<double> load(count, 0.0);
  std::vector<uint8_t> owner(n);
  for (const uint32_t i : order) {
    const size_t lane =
        static_cast<size_t>(std::min_element(load.begin(), load.end()) - load.begin());
    owner[i] = static_cast<uint8_t>(lane);
    load[lane] += work[i];
  }
  return owner;
}

// Lanes (Refiner::lane): quads dealt out by their work (deal(); a split
// crosses to another lane only on a quad's side), refined in rounds until no
// split is left in any inbox, then each lane's quads emitted by the lane. The
// mesh is the one a single refiner makes: a mark ends split exactly when a
// criterion over the threshold or a forced split reaches it, whatever the
// order (top_down()). `cpu`: the CPU time of the lanes' threads other than
// the calling one.
RefinedMesh refine_in_lanes(Refiner& r, const Selection& selection, size_t count,
                            Executor& executor, double& cpu_seconds) {
  // Kept for this thread's next frame (allocated once, not faulted in again).
  // (The lanes' threads name them through references: a thread_local named in
  // a lambda is the running thread's.)
  thread_local std::vector<MarkBlocks> kept_blocks;
  thread_local std::vector<std::vector<uint32_t>> kept_indices;
  std::vector<MarkBlocks>& blocks = kept_blocks;
  std::vector<std::vector<uint32_t>>& indices = kept_indices;
  if (blocks.size() < count) blocks.resize(count);
  if (indices.size() < count) indices.resize(count);
  Lanes lanes;
  lanes.owner = deal(selection, count);
  for (size_t i = 0; i < count; ++i) lanes.inboxes.push_back(std::make_unique<Lanes::Inbox>());
  r.seed_top_down();
  std::vector<Refiner> lane;
  lane.reserve(count);
  for (size_t i = 0; i < count; ++i) {
    blocks[i].reset();
    lane.push_back(r.lane(lanes, static_cast<uint32_t>(i), blocks[i]));
  }
  const std::thread::id caller = std::this_thread::get_id();
  std::vector<double> cpu(count, 0.0);
  const auto pending = [&] {
    return std::any_of(lanes.inboxes.begin(), lanes.inboxes.end(),
                       [](const auto& in) { return in->any.load(); });
  };
  const auto in_lanes = [&](const std::function<void(size_t)>& body) {
    executor.parallel_for(count, [&](size_t i) {
      const double start = thread_cpu_seconds();
      body(i);
      if (std::this_thread::get_id() != caller) cpu[i] += thread_cpu_seconds() - start;
    });
  };
  bool first = true;
  while (first || pending()) {
    first = false;
    in_lanes([&](size_t i) { lane[i].run_lane(); });
  }
  std::vector<RefinedQuad> at(selection.quads.size());
  in_lanes([&](size_t i) { lane[i].emit_lane(indices[i], at); });
  for (const Refiner& l : lane) r.merge(l);
  r.count_unresolved();
  cpu_seconds = 0;
  for (double c : cpu) cpu_seconds += c;
  return r.gather(lanes, indices, at);
}
}  // namespace

Result<RefinedMesh> refine(const View& view, TerrainModel& terrain, const Selection& selection,
                           const RefineOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  const double cpu_start = thread_cpu_seconds();
  RefineCache local(0);
  RefineCache& cache = options.cache ? *options.cache : local;
  // The marks' blocks and the step tables stay with the thread for its next frame.
  thread_local SlotMarks marks;
  thread_local StepTables steps;
  thread_local size_t last_indices = 0;
  RefineOptions o = options;
  // With the criteria evaluated elsewhere nothing is recorded: a recorded
  // decision's margins need the CPU's terms of its criterion (pixels() with
  // `out`), which would evaluate every criterion a second time.
  if (o.criteria) o.history = nullptr;
  RefineHistory::Impl* history = o.history ? &o.history->impl() : nullptr;
  if (history) {
    const RefineHistory::Impl::Seen seen{view.eye, view.right, view.up, view.forward,
                                         options.pixel_error};
    if (history->dormant > 0 && history->seen == seen) {  // stopped: record from this frame
      history->dormant = 0;
      history->judged = false;
      history->low = 0;
      history->spell = 0;
    }
    history->seen = seen;
  }
  const bool asleep = history && history->dormant > 0;
  if (asleep) {  // decided from scratch, nothing recorded
    --history->dormant;
    o.history = nullptr;
  }
  std::vector<Quad> quads(selection.quads.size());
  double criteria_seconds = 0;
  Refiner r(view, terrain, selection, o, cache.impl(), marks, steps, quads);
  RELIEF_CHECK(r.prepare());
  RefinedMesh mesh;
  double lanes_cpu = 0;                       // of the lanes' threads other than this one
  std::vector<std::vector<uint8_t>> classes;  // RefineOptions::criteria's
  if (o.criteria && !r.reuse_all()) {
    const auto at = std::chrono::steady_clock::now();
    RELIEF_CHECK(r.evaluate_criteria(*o.criteria, classes));
    criteria_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - at).count();
  }
  if (r.reuse_all()) {
    mesh = r.reused_mesh();
  } else {
    const size_t lanes = lane_count(o, selection);
    if (lanes > 1) {
      mesh = refine_in_lanes(r, selection, lanes, *o.executor, lanes_cpu);
    } else {
      if (o.variant == RefineVariant::kTopDown) {
        r.top_down();
      } else {
        r.bottom_up();
      }
      mesh = r.mesh(last_indices);
      last_indices = mesh.indices.size();
    }
    if (o.executor) remember_work(selection, mesh);  // for deal() in a later frame
  }
  r.save_history(mesh);
  cache.impl().end_frame(terrain);
  if (o.history) judge_reuse(*history, mesh.stats);
  mesh.stats.history_asleep = asleep;
  mesh.stats.criteria_seconds = criteria_seconds;
  mesh.stats.seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  mesh.stats.cpu_seconds = thread_cpu_seconds() - cpu_start + lanes_cpu;
  return mesh;
}

}  // namespace relief::lod
