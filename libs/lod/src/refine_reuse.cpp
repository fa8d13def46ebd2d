// Reusing decisions (RefineHistory): which blocks of which quads keep the
// last frames' decisions, made again as they were, and this frame's
// decisions saved for the next.
#include <algorithm>
#include <cmath>

#include "refiner.h"

namespace relief::lod {

RefineHistory::RefineHistory() : impl_(std::make_unique<Impl>()) {}
RefineHistory::~RefineHistory() = default;
void RefineHistory::clear() {
  impl_ = std::make_unique<Impl>();
}

namespace refinement {

namespace {

bool same(const Vec3& a, const Vec3& b) {
  return a.x == b.x && a.y == b.y && a.z == b.z;
}

// A history whose frames reused less than this share of their decisions
// kLowFrames times in a row (once, right after a dormant spell) goes dormant
// for kDormantFrames frames, then twice as many each time, up to
// kMaxDormantFrames (RefineHistory::Impl::dormant and spell).
constexpr double kMinReused = 0.25;
constexpr uint32_t kLowFrames = 3, kDormantFrames = 14, kMaxDormantFrames = 112;

}  // namespace

geo::TileKey Refiner::neighbour_key(const SelectedQuad& s, size_t k) const {
  const int32_t j = s.neighbours[k];
  return j >= 0 ? selection_.quads[static_cast<size_t>(j)].key : geo::TileKey{-1, 0, 0};
}

// Whether the record was made for the quad as selected now: the same
// neighbours (so the same marks mirror, block and split across), the same
// data (errors by address: the record holds them) and side heights.
bool Refiner::same_inputs(const QuadDecisions& r, size_t i) const {
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

// Which blocks reuse their decisions: those of quads with the same inputs,
// within their margins of the motion since their view (how far the eye
// moved, and the angle the view turned: the basis change is a rotation by
// w with |right' - right|^2 + |up' - up|^2 + |forward' - forward|^2 =
// 8 sin^2(w / 2)), or at the same view and threshold.
void Refiner::match_history() {
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
    motions.push_back({length(view_.eye - v.eye), 2 * std::asin(std::min(1.0, sine)) + kAngleSlack,
                       same(view_.eye, v.eye) && same(view_.right, v.right) &&
                           same(view_.up, v.up) && same(view_.forward, v.forward) &&
                           v.pixel_error == o_.pixel_error});
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
void Refiner::apply_history() {
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

// This frame's records replace the last ones.
void Refiner::save_history(const RefinedMesh& mesh) {
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

}  // namespace refinement
}  // namespace relief::lod
