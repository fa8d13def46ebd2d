#pragma once
// A frame-time budget for a moving view: while the view moves and its
// frames take longer than the budget, the pixel-error threshold relaxes
// further, on top of the speed's relaxation (speed_lod.h), until they fit;
// while frames are well within the budget it tightens, below the speed's
// relaxation if the time allows but never below the still threshold (the
// caller's `floor`), so a moving view holds the frame rate asked for with
// the finest detail that fits in it; it returns to exactly 1 when the view
// stops, so the still frame is the complete one at the still threshold (a
// still view is never coarsened for speed).
//
// The factor moves multiplicatively by the frame's overrun, capped per
// frame: the frame time falls slowly with the threshold (on llvmpipe the
// Pyrenees flight of bench/view at 1.5 times the threshold took 0.8 times
// as long), and the frame measured is one the previous factor drew (the
// overlap of docs/viewer.md delays the effect by a frame), so larger steps
// overshoot. A band around the budget (over, under) holds the factor where
// frames fit instead of hunting.
namespace relief::view {

struct FrameBudgetOptions {
  double target_ms = 0;         // 0: no budget (relief view --target-fps sets one)
  double max_factor = 3;        // at most this times the threshold it is given
  double over = 1.1;            // frames longer than over * target relax the threshold
  double under = 0.85;          // frames shorter than under * target tighten it
  double max_step = 1.3;        // the most one frame relaxes it by
  double recover_seconds = 1;   // time constant towards the floor while frames are fast
  double settle_seconds = 0.3;  // of the return when the view stops
};

class FrameBudget {
 public:
  explicit FrameBudget(const FrameBudgetOptions& options = {}) : options_(options) {}
  // The factor for the next frame, `dt` seconds after the previous one,
  // which took `frame_ms` (0: not known, nothing changes), the view moving
  // or not. `floor` (at most 1) is the smallest factor fast frames may
  // bring it to: the still threshold over the threshold it multiplies.
  double update(double frame_ms, double dt, bool moving, double floor = 1);
  double factor() const { return factor_; }
  const FrameBudgetOptions& options() const { return options_; }

 private:
  FrameBudgetOptions options_;
  double factor_ = 1;
};

}  // namespace relief::view
