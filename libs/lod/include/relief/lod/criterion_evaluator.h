#pragma once
// The split criterion of edge-mark refinement (refine.h) evaluated for every
// diamond of every quad at once, elsewhere than on this thread: seed 003
// §3.5's marker pass, one GPU thread per edge mark (render::GlRefineCriteria,
// a GL compute shader). refine() hands over each quad's inputs and takes one
// class per diamond: under the threshold, over it, or too near it to trust
// another processor's rounding. refine() evaluates the near ones itself, so
// the mesh is the one it makes alone, bit for bit.
#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "relief/base/result.h"
#include "relief/lod/camera.h"

namespace relief::lod {

enum class CriterionClass : uint8_t { kUnder = 0, kOver = 1, kNear = 2 };

// One quad's inputs. Its grid (lod/src/edge_marks.h) has (2n + 1) x (n + 1)
// points, n = 2^k, x east from the west side, y south from the north side;
// diamonds are numbered by slot, class by class (CriterionFrame::class_offsets).
struct CriterionQuad {
  double west = 0, north = 0;  // degrees
  double cell = 0;             // degrees per grid cell
  double level_error = 0;      // metres, added to every diamond's error
  // Per slot, 8 bytes: a float (the diamond's error, metres), then two int16
  // (its lowest and highest height, metres). Empty: no data (all zero).
  // They never change while their owner lives (one per data tile, shared by
  // the quads of that tile): an evaluator may keep a copy, keyed by the
  // owner, as long as a weak reference to it has not expired.
  std::span<const uint8_t> errors;
  std::shared_ptr<const void> errors_owner;
  // West, east, north, south: metres by which the side's grid points move
  // by taking a coarser neighbour's data, by their y (west, east) or x;
  // empty where the side keeps its own data.
  std::array<std::span<const float>, 4> sides;
  // Sines and cosines of the west and north sides, and of i cells for
  // i = 0 .. 2n (interleaved: sin, cos); the prime vertical radius of
  // curvature of every row y.
  double west_sin = 0, west_cos = 1, north_sin = 0, north_cos = 1;
  std::span<const double> steps;
  std::span<const double> normals;
  // Per class: cos and sin of the spread of the normals over a diamond's
  // area (screen_error.h, AreaNormals), interleaved.
  std::span<const double> spreads;
};

struct CriterionFrame {
  const View* view = nullptr;
  double pixel_error = 1;
  int k = 0;
  // The first slot of each class (2k - 2 classes, the halves' centres
  // excluded: always split), then the end of the last.
  std::span<const uint32_t> class_offsets;
  // Terms of a diamond's ball (refine_criterion.cpp): metres of chord per
  // radian, and metres for the rounding of its centre.
  double arc = 0, rounding = 0;
  // Values within pixel_error x (1 +- band) are kNear.
  double band = 1e-6;
};

class CriterionEvaluator {
 public:
  virtual ~CriterionEvaluator() = default;
  // classes[q]: one CriterionClass per slot of quads[q] below class_offsets.back().
  virtual Status evaluate(const CriterionFrame& frame, std::span<const CriterionQuad> quads,
                          std::vector<std::vector<uint8_t>>& classes) = 0;
};

}  // namespace relief::lod
