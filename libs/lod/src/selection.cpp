#include "relief/lod/selection.h"

#include <algorithm>
#include <cassert>
#include <chrono>
#include <deque>
#include <functional>
#include <optional>
#include <unordered_set>

#include "level_grid.h"
#include "quad_map.h"

#include <fmt/format.h>

#include "relief/geo/ellipsoid.h"
#include "relief/lod/screen_error.h"

namespace relief::lod {

namespace {

using geo::TileKey;

// A view with a window selects what its window shows (a rank of sort-first
// rendering or one display of a wall loads only its part), with the whole
// view's error metric.
bool outside_frustum(const Box& b, const std::array<Plane, 5>& planes) {
  return outside(planes, b.lo, b.hi);
}

class Selector {
 public:
  Selector(const View& v, TerrainModel& t, const SelectionOptions& o)
      : view_(&v), planes_(window_planes(v)), terrain_(t), o_(o) {
    claim_map();
  }
  // Without a view: every quad visible, split by `rule` (restricted_quadtree).
  Selector(TerrainModel& t, const SelectionOptions& o, std::function<bool(const TileKey&)> rule)
      : view_(nullptr), terrain_(t), o_(o), rule_(std::move(rule)) {
    claim_map();
  }

  Status run() {
    const TileKey root{0, 0, 0};
    if (const auto w = terrain_.window(root); w.tile && !terrain_.available(*w.tile)) {
      terrain_.request(*w.tile, INFINITY);  // nothing to draw yet
      ++waiting_;
      return {};
    }
    RELIEF_CHECK(visit(root));
    RELIEF_CHECK(restrict_levels());
    return {};
  }

  ~Selector() { thread_map_in_use() = false; }
  Selector(const Selector&) = delete;
  Selector& operator=(const Selector&) = delete;

  Selection result() {
    Selection s;
    // In key order: sorted as packed keys (level, x, y: the order of
    // TileKey's comparison), not as quads ten times larger.
    std::vector<std::pair<TileKey, const Leaf*>> tree;  // one scan of the map's slots
    tree.reserve(leaf_count_ * 2);
    leaves_.for_each([&](const TileKey& key, const Leaf& leaf) { tree.emplace_back(key, &leaf); });
    grid_.build([&](auto f) {
      for (const auto& [key, leaf] : tree) f(key, leaf->internal);
    });
    std::vector<std::pair<uint64_t, const Leaf*>> visible;
    visible.reserve(leaf_count_);
    for (const auto& [key, leaf] : tree) {
      if (leaf->internal) continue;
      if (!leaf->visible) {
        ++s.stats.culled;
        continue;
      }
      visible.emplace_back(QuadMap<Leaf>::pack(key), leaf);
    }
    std::sort(visible.begin(), visible.end(),
              [](const auto& a, const auto& b) { return a.first < b.first; });
    s.quads.reserve(visible.size());
    for (const auto& [packed, leaf] : visible) {
      SelectedQuad& q = s.quads.emplace_back();
      q.key = QuadMap<Leaf>::unpack(packed);
      q.error_pixels = leaf->error_pixels;
      q.priority = leaf->priority;
      classify_neighbours(q);
    }
    if (o_.neighbour_indices) link_neighbours(s.quads);
    // Quads may go deeper than the terrain (SelectionOptions::max_level).
    int deepest_quad = terrain_.max_level();
    for (const auto& q : s.quads) deepest_quad = std::max(deepest_quad, q.key.level);
    s.stats.quads_per_level.assign(static_cast<size_t>(deepest_quad + 1), 0);
    for (const auto& q : s.quads) {
      ++s.stats.quads_per_level[static_cast<size_t>(q.key.level)];
      s.stats.triangles += terrain_.mesh().triangle_count(q.finer_sides);
      s.stats.max_error_pixels = std::max(s.stats.max_error_pixels, q.error_pixels);
    }
    s.stats.quads = static_cast<uint32_t>(s.quads.size());
    s.stats.waiting = waiting_;
    s.stats.deferred = deferred_;
    return s;
  }

 private:
  struct Leaf {  // 24 bytes: the map's values are scanned twice per selection
    double error_pixels = 0;
    double priority = 0;
    bool visible = false;
    bool split_for_samples = false;  // coarser samples than pixels
    bool internal = false;           // split: an inner node of the tree, not a leaf
  };

  // Culls and measures one quad: visible, and its projected error bound.
  Result<Leaf> assess(const TileKey& key) {
    if (!view_) return Leaf{.error_pixels = rule_(key) ? INFINITY : 0.0, .visible = true};
    if (terrain_.draws_ancestor(key) && !terrain_.blocking()) {
      // Deeper than the data, a quad whose tile is not resident can only be
      // a child of a culled quad (visible quads have their data): culled.
      if (const DataWindow w = terrain_.window(key); w.tile && !terrain_.available(*w.tile)) {
        return Leaf{};
      }
    }
    const View& view_ref = *view_;
    TerrainModel::QuadInfo* info = RELIEF_TRY(terrain_.quad(key));
    const HeightRange& range = info->range;
    const Box& box = info->box;
    Leaf leaf;
    if (outside_frustum(box, planes_) || hidden_by_horizon(box, range)) return leaf;
    leaf.visible = true;
    if (!terrain_.blocking()) leaf.priority = priority(box);  // only loads need it
    // Brute force: the dataset alone, every quad down to the finest level.
    if (o_.full_resolution) {
      leaf.visible = terrain_.window(key).tile.has_value();
      leaf.error_pixels = key.level < terrain_.max_level() ? INFINITY : 0.0;
      return leaf;
    }
    const double d = distance_to(box, view_ref.eye);
    if (o_.mode == LodMode::edge_marks) {
      // Refinement inside the quad can reach its full mesh, no closer to the
      // finest data than level_error: that share decides the split.
      const double error = RELIEF_TRY(terrain_.level_error(key));
      leaf.error_pixels =
          vertical_error_pixels(view_ref, box, info->normals, error) / o_.level_error_share;
    } else {
      const double error = RELIEF_TRY(terrain_.quad_error(key, *info));
      leaf.error_pixels = vertical_error_pixels(view_ref, box, info->normals, error);
    }
    // Up to the finest level of the data (and of the draped texture), a quad
    // must also provide at least one sample per pixel it covers (seed 003
    // §1.4.2 step 5): shading and imagery are sampled per pixel from them.
    auto coarser_than_pixels = [&](const tiles::Store& s) {
      if (key.level >= s.manifest().max_level) return false;
      const double spacing = 2 * 3.14159265358979323846 * geo::wgs84::kSemiMajorAxis /
                             std::ldexp(s.grid().width(), key.level);
      return (d <= 0 || spacing * view_ref.pixels_per_radian / d > 1) && s.has_tile(key);
    };
    const tiles::Store* data = terrain_.store();
    leaf.split_for_samples =
        (data && coarser_than_pixels(*data)) || (o_.texture && coarser_than_pixels(*o_.texture));
    return leaf;
  }

  // Outside the view: beyond the frustum or behind the horizon.
  bool culled(const TerrainModel::QuadInfo& info) const {
    return outside_frustum(info.box, planes_) || hidden_by_horizon(info.box, info.range);
  }

  bool hidden_by_horizon(const Box& b, const HeightRange& range) const {
    // Every corner of the box behind the ellipsoid shrunk below the lowest
    // terrain (boxes of large quads are too loose to judge: never culled).
    if (b.hi.x - b.lo.x > 2e6) return false;
    const double below = std::max(0.0, -range.lo) + 100;
    for (int c = 0; c < 8; ++c) {
      const Vec3 p{c & 1 ? b.hi.x : b.lo.x, c & 2 ? b.hi.y : b.lo.y, c & 4 ? b.hi.z : b.lo.z};
      if (!below_horizon(view_->eye, p, below)) return false;
    }
    return true;
  }

  // View priority of loading a quad's data (seed 002: screen coverage,
  // distance from the screen centre, depth): the pixels its box covers,
  // weighted down away from the centre. Higher first.
  double priority(const Box& box) const {
    const Vec3 centre = (box.lo + box.hi) * 0.5, to = centre - view_->eye;
    const double d = std::max(distance_to(box, view_->eye), view_->near);
    const double size = length(box.hi - box.lo) * view_->pixels_per_radian / d;
    const double pixels = std::min(size * size, double(view_->width) * view_->height);
    const double off = std::acos(std::clamp(dot(to, view_->forward) / length(to), -1.0, 1.0)) /
                       std::atan(view_->tan_half_y);
    return pixels / (1 + off * off);
  }

  // Requests, at the lowest priority, the coarsest tile on the way from the
  // root to `tile` that is not available (ancestors load first).
  void request_first_missing(const TileKey& tile) {
    std::optional<TileKey> missing;
    for (std::optional<TileKey> k = tile; k; k = k->parent()) {
      if (!terrain_.available(*k)) missing = k;
    }
    if (missing) terrain_.request(*missing, 0);
  }

  // Requests `tile` at priority `p` and, above it, each of its ancestors that
  // is not available at twice the priority of the one below: a neighbour's
  // parent need not be resident or requested (it is not on the way to the
  // quad being split), and the loader takes the highest priority first, so
  // ancestors still load first.
  void request_with_ancestors(const TileKey& tile, double p) {
    std::vector<TileKey> chain;
    for (std::optional<TileKey> k = tile; k && !terrain_.available(*k); k = k->parent()) {
      chain.push_back(*k);
    }
    for (const TileKey& k : chain) {
      terrain_.request(k, p);
      p *= 2;
    }
  }

  // Interactive frames draw only resident data: a quad splits only when the
  // data of each of its visible children is available now; the missing ones
  // are requested. Deeper than the store, children draw the same tile.
  Result<bool> children_available(const TileKey& key) {
    if (terrain_.blocking()) return true;
    if (frozen_.contains(key)) return false;
    // Children of a culled quad are culled too (their bounds nest):
    // splitting it for the restriction needs no data.
    if (const Leaf* leaf = leaves_.find(key); leaf && !leaf->internal && !leaf->visible) {
      return true;
    }
    // Nor does a visible quad whose children are all culled: nothing of it
    // is drawn once it splits (the quad's own tile is there for its
    // children's sides shared with coarser quads).
    if (RELIEF_TRY(children_culled(key))) return true;
    if (const DataWindow own = terrain_.window(key); own.tile && !terrain_.available(*own.tile)) {
      // A culled quad without its data: that loads first (ancestors first).
      request_first_missing(*own.tile);
      ++waiting_;
      return false;
    }
    bool all = true;
    for (int c = 0; c < 4; ++c) {
      const TileKey child = key.child(c & 1, c >> 1);
      const DataWindow w = terrain_.window(child);
      if (!w.tile) continue;
      if (terrain_.available(*w.tile)) {
        if (o_.drawable_now && !terrain_.draws_ancestor(child) &&
            !culled(*RELIEF_TRY(terrain_.quad(child))) && !o_.drawable_now(*w.tile)) {
          ++deferred_;
          all = false;
        }
        continue;
      }
      if (terrain_.draws_ancestor(child)) {
        // An unloaded quad, culled before (its bounds need the tile): only
        // restriction splits it. Lowest priority.
        request_first_missing(*w.tile);
        ++waiting_;
        return false;
      }
      TerrainModel::QuadInfo* info = RELIEF_TRY(terrain_.quad(child));
      if (culled(*info) || !RELIEF_TRY(wants_own_tile(child))) continue;
      const double p = priority(info->box);
      terrain_.request(*w.tile, p);
      ++waiting_;
      all = false;
      RELIEF_CHECK(want_below(child, p));
    }
    return all;
  }

  // Whether every child of `key` is outside the view: it then splits into
  // quads that draw nothing. Children without a tile of their own, or whose
  // bounds need their tile, count as visible.
  Result<bool> children_culled(const TileKey& key) {
    if (key.level >= deepest()) return false;
    for (int c = 0; c < 4; ++c) {
      const TileKey child = key.child(c & 1, c >> 1);
      if (!terrain_.window(child).tile || terrain_.draws_ancestor(child)) return false;
      TerrainModel::QuadInfo* info = RELIEF_TRY(terrain_.quad(child));
      if (!culled(*info)) return false;
    }
    return true;
  }

  // An interactive frame reaches a visible quad without its data only when
  // all its children are culled (wants_own_tile): nothing of it is on
  // screen, so should it stay a leaf (frozen, or coarsened back by the
  // restriction) it is culled rather than drawn without data.
  Result<Leaf> drawable(const TileKey& key, Leaf leaf) {
    if (!leaf.visible || terrain_.blocking()) return leaf;
    const DataWindow w = terrain_.window(key);
    if (!w.tile || terrain_.available(*w.tile)) return leaf;
    assert(children_culled(key).value_or(true));
    leaf.visible = false;
    return leaf;
  }

  // Whether the view will want the tile of a visible quad that the
  // selection reaches: not when the quad splits into culled children only.
  Result<bool> wants_own_tile(const TileKey& key) {
    if (key.level >= deepest()) return true;
    const Leaf leaf = RELIEF_TRY(assess(key));
    const bool splits =
        leaf.visible && (leaf.error_pixels > o_.pixel_error || leaf.split_for_samples);
    return !splits || !RELIEF_TRY(children_culled(key));
  }

  // Requests the data the view will want below a quad whose own data is not
  // resident yet, each tile ranked below its ancestors (which load first), so
  // a deep view does not wait one round trip per level. Needs no tiles: above
  // the store's finest level, errors come from the index.
  Status want_below(const TileKey& key, double cap) {
    if (key.level + 1 > terrain_.data_max_level()) return {};
    const Leaf leaf = RELIEF_TRY(assess(key));
    if (!leaf.visible || (leaf.error_pixels <= o_.pixel_error && !leaf.split_for_samples))
      return {};
    // `key` will split: the restricted property then splits the parents of
    // its visible same-level neighbours (its children sit beside them), so
    // their data is wanted too. A quad that stays a leaf forces nothing.
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) {
        const auto n = key.neighbour(dx, dy);
        if (!n || (!dx && !dy)) continue;
        const DataWindow w = terrain_.window(*n);
        if (!w.tile || terrain_.available(*w.tile) || terrain_.draws_ancestor(*n)) continue;
        TerrainModel::QuadInfo* info = RELIEF_TRY(terrain_.quad(*n));
        if (culled(*info) || !RELIEF_TRY(wants_own_tile(*n))) continue;
        request_with_ancestors(*w.tile, cap * 0.25);
      }
    }
    for (int c = 0; c < 4; ++c) {
      const TileKey child = key.child(c & 1, c >> 1);
      const DataWindow w = terrain_.window(child);
      if (!w.tile || terrain_.draws_ancestor(child)) continue;
      TerrainModel::QuadInfo* info = RELIEF_TRY(terrain_.quad(child));
      if (culled(*info) || !RELIEF_TRY(wants_own_tile(child))) continue;
      const double p = std::min(priority(info->box), cap * 0.5);
      terrain_.request(*w.tile, p);
      RELIEF_CHECK(want_below(child, p));
    }
    return {};
  }

  // Splits `key` while its error asks for it; the quads it splits are also
  // appended to `added` when given.
  Status visit(const TileKey& key, std::vector<TileKey>* added = nullptr) {
    if (leaf_count_ > o_.max_quads) {
      return fail(
          fmt::format("level of detail: more than {} quads; raise --pixel-error", o_.max_quads));
    }
    const Leaf leaf = RELIEF_TRY(assess(key));
    bool split = leaf.visible && key.level < deepest() &&
                 (leaf.error_pixels > o_.pixel_error || leaf.split_for_samples ||
                  (view_ && o_.also_split && o_.also_split(key)));
    if (split) split = splittable(key) && RELIEF_TRY(children_available(key));
    if (!split) {
      set_leaf(key, RELIEF_TRY(drawable(key, leaf)));
      return {};
    }
    set_internal(key);
    if (added) added->push_back(key);
    for (int c = 0; c < 4; ++c) RELIEF_CHECK(visit(key.child(c & 1, c >> 1), added));
    return {};
  }

  // Edge marks refine a quad's own tile (its diamond errors, its sides shared
  // with coarser quads): over a store of sparse depth, a quad whose tile has
  // no child tile is not split, since its children would draw its window.
  // There its samples are the finest data (its level error counts only data
  // below it), so its refinement reaches them. The fused store's padding
  // (pipeline/fused_elevation.cpp: the children and neighbours of each
  // tile's parent) gives such a tile no tile two levels finer beside it, so
  // the restriction does not need to split it (docs/rendering.md; where it
  // would, restrict_levels keeps the finer side coarser).
  bool splittable(const TileKey& key) const {
    if (frozen_.contains(key)) return false;
    if (o_.mode != LodMode::edge_marks || !terrain_.sparse_depth()) return true;
    for (int c = 0; c < 4; ++c) {
      if (terrain_.draws_ancestor(key.child(c & 1, c >> 1))) return false;
    }
    return true;
  }

  // Edge marks refine inside quads down to every sample: no virtual levels.
  int deepest() const {
    if (o_.max_level >= 0) return o_.max_level;
    return o_.mode == LodMode::edge_marks ? terrain_.data_max_level() : terrain_.max_level();
  }

  // The leaf whose area contains quad `key` (key itself or an ancestor), if
  // any. The map holds the split quads too, so the walk up stops at the
  // first quad it finds: in a restricted tree within three probes.
  std::optional<TileKey> leaf_containing(TileKey key) {
    for (;;) {
      if (const Leaf* found = leaves_.find(key)) {
        if (found->internal) return std::nullopt;  // subdivided below `key`
        return key;
      }
      if (key.level == 0) return std::nullopt;
      key = {key.level - 1, key.x >> 1, key.y >> 1};
    }
  }

  void set_leaf(const TileKey& key, const Leaf& leaf) {
    const Leaf* old = leaves_.find(key);
    if (!old || old->internal) ++leaf_count_;
    leaves_.set(key, leaf);
  }
  void set_internal(const TileKey& key) {
    const Leaf* old = leaves_.find(key);
    if (old && !old->internal) --leaf_count_;
    Leaf inner;
    inner.internal = true;
    leaves_.set(key, inner);
  }

  // A split for the restriction: the children may need splitting for their
  // own error too (a child's bound is not below its parent's: its sides may
  // take the parent's data), so they are visited like any quad.
  Status split(const TileKey& key, std::vector<TileKey>& work) {
    set_internal(key);
    work.push_back(key);
    for (int c = 0; c < 4; ++c) RELIEF_CHECK(visit(key.child(c & 1, c >> 1), &work));
    return {};
  }

  // Makes `key` a leaf again, dropping the quads below it; it will not split
  // again in this selection.
  Status coarsen(const TileKey& key) {
    std::vector<TileKey> below;
    leaves_.for_each([&](const TileKey& k, const Leaf& leaf) {
      if (k.level > key.level &&
          TileKey{key.level, k.x >> (k.level - key.level), k.y >> (k.level - key.level)} == key) {
        below.push_back(k);
        if (!leaf.internal) --leaf_count_;
      }
    });
    for (const TileKey& k : below) leaves_.erase(k);
    const Leaf assessed = RELIEF_TRY(assess(key));
    set_leaf(key, RELIEF_TRY(drawable(key, assessed)));
    frozen_.insert(key);
    return {};
  }

  // Splits leaves until quads sharing an edge or a corner differ by at most
  // one level. Checked on the split quads: the tree is restricted when the
  // eight same-level neighbours of every split quad are in it (split or
  // leaves), since a leaf's neighbours have its parent or the parent's
  // neighbours as parents, and conversely each neighbour of a split quad is
  // the parent of a neighbour of its deepest leaf in that direction. One
  // probe per neighbour, a third as many quads as leaves.
  Status restrict_levels() {
    std::vector<TileKey> work;
    auto check_all = [&] {
      work.clear();
      leaves_.for_each([&](const TileKey& key, const Leaf& leaf) {
        if (leaf.internal) work.push_back(key);
      });
    };
    check_all();
    while (!work.empty()) {
      const TileKey key = work.back();
      work.pop_back();
      if (const Leaf* leaf = leaves_.find(key); !leaf || !leaf->internal) continue;
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
          if (!dx && !dy) continue;
          // Siblings are in the tree with `key`: no probe.
          const int sx = static_cast<int>(key.x & 1) + dx, sy = static_cast<int>(key.y & 1) + dy;
          if (key.level > 0 && sx >= 0 && sx <= 1 && sy >= 0 && sy <= 1) continue;
          const auto n = key.neighbour(dx, dy);
          if (!n || leaves_.find(*n)) continue;
          // Inside a leaf coarser than `key`: split it.
          const std::optional<TileKey> victim = leaf_containing(*n);
          if (!victim) continue;  // not drawn at all (an interrupted selection)
          if (!splittable(*victim) || !RELIEF_TRY(children_available(*victim))) {
            // Interactive: the coarse side has no finer data yet, so the
            // fine side comes back up; everything is checked again. (Not
            // splittable: should the padding not hold, the same.)
            RELIEF_CHECK(coarsen(key));
            check_all();
            dx = dy = 2;  // `key` is a leaf now: next in the list
            break;
          }
          RELIEF_CHECK(split(*victim, work));
          work.push_back(key);  // the victim's child may still be too coarse
          if (leaf_count_ > o_.max_quads) {
            return fail(fmt::format("level of detail: more than {} quads; raise --pixel-error",
                                    o_.max_quads));
          }
          dx = dy = 2;
          break;
        }
      }
    }
    return {};
  }

  // Level of the leaf at the neighbour position (dx, dy) of `key`: the same,
  // one coarser, or one finer (the neighbour is subdivided); nullopt past a pole.
  std::optional<int> neighbour_level(const TileKey& key, int dx, int dy) {
    const auto n = key.neighbour(dx, dy);
    if (!n) return std::nullopt;
    switch (grid_.at(*n)) {
      case LevelGrid::Cell::kLeaf:
        return key.level;
      case LevelGrid::Cell::kSplit:
        return key.level + 1;  // subdivided: finer
      case LevelGrid::Cell::kNone:
        // Restricted: inside the parent, a leaf.
        if (grid_.at({n->level - 1, n->x >> 1, n->y >> 1}) == LevelGrid::Cell::kLeaf) {
          return key.level - 1;
        }
        break;
      case LevelGrid::Cell::kUnknown:
        break;
    }
    if (const Leaf* found = leaves_.find(*n)) {
      return found->internal ? key.level + 1 : key.level;
    }
    const std::optional<TileKey> leaf = leaf_containing(*n);
    if (!leaf) return key.level + 1;
    return leaf->level;
  }

  // The lowest data level of the leaves at the neighbour position (dx, dy) of
  // `key` that touch it (one leaf, or the children of a subdivided neighbour
  // on the shared side or corner).
  int min_data_level(const TileKey& key, int dx, int dy) {
    const TileKey n = *key.neighbour(dx, dy);
    if (const std::optional<TileKey> leaf = leaf_containing(n)) return terrain_.data_level(*leaf);
    int lowest = INT32_MAX;
    for (int c = 0; c < 4; ++c) {
      const int cx = c & 1, cy = c >> 1;
      // The children of n touching `key`: on its side facing key.
      if ((dx == -1 && cx != 1) || (dx == 1 && cx != 0) || (dy == -1 && cy != 1) ||
          (dy == 1 && cy != 0)) {
        continue;
      }
      lowest = std::min(lowest, terrain_.data_level(n.child(cx, cy)));
    }
    return lowest;
  }

  // The per-quad neighbour index array of the seed's mesh creation (§1.4.3).
  void link_neighbours(std::vector<SelectedQuad>& quads) {
    QuadMap<int32_t> index(quads.size());
    for (size_t i = 0; i < quads.size(); ++i) index.set(quads[i].key, static_cast<int32_t>(i));
    auto at = [&](const TileKey& k) {
      const int32_t* i = index.find(k);
      return i ? *i : -1;
    };
    const struct {
      int dx, dy;
      int child[2][2];  // the two children of a finer neighbour that touch this side
    } sides[] = {{-1, 0, {{1, 0}, {1, 1}}},
                 {1, 0, {{0, 0}, {0, 1}}},
                 {0, -1, {{0, 1}, {1, 1}}},
                 {0, 1, {{0, 0}, {1, 0}}}};
    for (SelectedQuad& q : quads) {
      for (int s = 0; s < 4; ++s) {
        const auto n = q.key.neighbour(sides[s].dx, sides[s].dy);
        if (!n) continue;
        if (const auto leaf = leaf_containing(*n)) {
          q.neighbours[2 * s] = at(*leaf);
        } else {
          for (int c = 0; c < 2; ++c) {
            q.neighbours[2 * s + c] = at(n->child(sides[s].child[c][0], sides[s].child[c][1]));
          }
        }
      }
    }
  }

  void classify_neighbours(SelectedQuad& q) {
    const int l = q.key.level;
    // Levels of the eight neighbours, looked up once: level[dy + 1][dx + 1].
    std::optional<int> level[3][3];
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) {
        if (dx || dy) level[dy + 1][dx + 1] = neighbour_level(q.key, dx, dy);
      }
    }
    auto coarser = [&](int dx, int dy) {
      const auto& n = level[dy + 1][dx + 1];
      return n && *n < l;
    };
    // Sparse depth (TerrainModel::data_level): heights take the parent data
    // where a quad touching the side or corner draws coarser data, whatever
    // its level (neighbouring data levels differ by at most one: the fused
    // store's padding, pipeline/fused_elevation.cpp).
    const bool by_data = terrain_.sparse_depth();
    const int own_data = terrain_.data_level(q.key);
    auto coarser_data = [&](int dx, int dy) {
      if (!by_data) return coarser(dx, dy);
      return level[dy + 1][dx + 1] && min_data_level(q.key, dx, dy) < own_data;
    };
    auto finer = [&](int dx, int dy) {
      const auto& n = level[dy + 1][dx + 1];
      return n && *n > l;
    };
    const struct {
      int dx, dy;
      uint8_t side;
    } sides[] = {{-1, 0, kWest}, {1, 0, kEast}, {0, -1, kNorth}, {0, 1, kSouth}};
    for (const auto& d : sides) {
      if (finer(d.dx, d.dy)) q.finer_sides |= d.side;
      if (coarser(d.dx, d.dy)) q.coarse_sides |= d.side;
      if (coarser_data(d.dx, d.dy)) q.parent_data_sides |= d.side;
    }
    // A corner takes the parent's data when any quad sharing it is coarser.
    const struct {
      int dx, dy;
      uint8_t corner;
    } corners[] = {
        {-1, -1, kNorthWest}, {1, -1, kNorthEast}, {-1, 1, kSouthWest}, {1, 1, kSouthEast}};
    for (const auto& c : corners) {
      if (coarser(c.dx, 0) || coarser(0, c.dy) || coarser(c.dx, c.dy)) q.coarse_corners |= c.corner;
      if (coarser_data(c.dx, 0) || coarser_data(0, c.dy) || coarser_data(c.dx, c.dy)) {
        q.parent_data_corners |= c.corner;
      }
    }
  }

  const View* view_;
  std::array<Plane, 5> planes_{};  // the view's frustum, or its window's
  TerrainModel& terrain_;
  const SelectionOptions& o_;
  std::function<bool(const TileKey&)> rule_;
  // The leaves and the split quads above them: the calling thread's map,
  // whose slots (~1 MB for 10 000 quads) stay allocated between selections
  // (a fresh map grew twice per frame: page faults and rehashes were ~8 % of
  // a selection). One selection per thread at a time.
  static QuadMap<Leaf>& thread_map() {
    thread_local QuadMap<Leaf> map;
    return map;
  }
  static bool& thread_map_in_use() {
    thread_local bool in_use = false;
    return in_use;
  }
  void claim_map() {
    assert(!thread_map_in_use() && "a selection inside another on one thread");
    thread_map_in_use() = true;
    leaves_.clear();
  }
  QuadMap<Leaf>& leaves_ = thread_map();
  size_t leaf_count_ = 0;
  LevelGrid grid_;  // the finished tree, for classifying neighbours
  std::unordered_set<TileKey, geo::TileKeyHash> frozen_;  // coarsened: stay leaves
  uint32_t waiting_ = 0;                                  // data requested, not resident
  uint32_t deferred_ = 0;                                 // resident, not drawable_now
};

}  // namespace

bool below_horizon(const Vec3& eye, const Vec3& point, double below) {
  // Scale space so the shrunk ellipsoid is the unit sphere; the point is hidden
  // when the segment from the eye to it passes through the sphere.
  const double a = geo::wgs84::kSemiMajorAxis - below, b = geo::wgs84::kSemiMinorAxis - below;
  const Vec3 e{eye.x / a, eye.y / a, eye.z / b}, p{point.x / a, point.y / a, point.z / b};
  const Vec3 d = p - e;
  const double dd = dot(d, d);
  if (dd == 0) return false;
  const double t = std::clamp(-dot(e, d) / dd, 0.0, 1.0);
  const Vec3 closest = e + d * t;
  return dot(closest, closest) < 1 && t > 0 && t < 1;
}

Result<Selection> restricted_quadtree(TerrainModel& terrain,
                                      const std::function<bool(const geo::TileKey&)>& split) {
  SelectionOptions o;
  o.neighbour_indices = true;
  Selector s(terrain, o, split);
  RELIEF_CHECK(s.run());
  return s.result();
}

Result<Selection> select_quads(const View& view, TerrainModel& terrain,
                               const SelectionOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  Selector s(view, terrain, options);
  RELIEF_CHECK(s.run());
  Selection result = s.result();
  result.stats.seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace relief::lod
