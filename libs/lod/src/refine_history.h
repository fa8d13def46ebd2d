#pragma once
// What RefineHistory keeps between frames (refine.h): the decisions the last
// frames made per quad, with the motion of the view they hold for, and the
// last frame's mesh. Made by refine_margins.cpp, reused by refine_reuse.cpp.
#include <array>
#include <cmath>
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "diamond_errors.h"
#include "quad_map.h"
#include "relief/lod/refine.h"
#include "side_edges.h"

namespace relief::lod {

// The decisions of the last frames (docs/rendering.md, "Reusing decisions";
// refine_margins.cpp). A quad's grid is cut into blocks of 2^s x 2^s cells;
// each block has the view its margins are relative to (an id into
// RefineHistory::Impl::views), how far the eye may move and the view turn
// from there, and the thresholds they hold for.
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

namespace refinement {

// Reusing decisions: the motion a recording quad's margins are checked for,
// per unit of its budget (adapted per quad between kMinBudget and kMaxBudget):
// the eye moving this share of a box's depth, the view turning this angle.
// and the threshold changing by this share (when it changed since the last frame).
constexpr double kMoveShare = 0.01, kTurn = 0.004, kBand = 0.03;
constexpr double kMinBudget = 1.0 / 16, kMaxBudget = 4;
// Views kept: a block decided longer ago is decided again.
constexpr size_t kViews = 64;
constexpr uint32_t kIdle = 2, kProbe = 4;

// After a frame refined with the history: frames that reused too little put
// it to sleep for the next ones (RefineHistory::Impl::dormant).
void judge_reuse(RefineHistory::Impl& h, const RefineStats& s);

}  // namespace refinement
}  // namespace relief::lod
