#pragma once
// How a frame is split over ranks (seed 001 §4): the screen into tiles
// (sort-first), or the quads the whole view selected (sort-last) by one of
// the three database decompositions of the seed. Pure functions: no MPI.
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "relief/base/result.h"
#include "relief/geo/tile_key.h"
#include "relief/lod/camera.h"

namespace relief::parallel {

enum class ScreenSplit {
  horizontal,  // strips the width of the view, stacked (the seed calls this "vertical")
  vertical,    // strips the height of the view, side by side
  grid,        // rows x columns, as square as the rank count allows
};

enum class QuadSplit {
  block,     // linear block: the store's extent cut into equal longitude ranges
  quadtree,  // quadtree enumeration of the store's extent cut into equal ranges
  active,    // active-patch enumeration: the selected quads cut into equal triangle counts
};

struct ParallelMode {
  enum class Kind { sort_first, sort_last, wall } kind = Kind::sort_first;
  ScreenSplit screen = ScreenSplit::horizontal;
  QuadSplit quads = QuadSplit::active;
  std::string wall_file;  // Kind::wall
};

// sort-first:h|v|grid, sort-last:block|quadtree|active or wall:FILE.json;
// a one-line error naming --parallel otherwise.
Result<ParallelMode> parse_parallel_mode(std::string_view text);
std::string to_string(const ParallelMode& mode);

// The screen tile of each of `ranks` ranks; together they cover the
// width x height view exactly once.
std::vector<lod::PixelRect> screen_tiles(int width, int height, ScreenSplit split, int ranks);

// The rank that draws each quad (parallel to `quads`, whose triangle counts
// are `triangles`), for a store covering `extent`.
std::vector<int> assign_quads(std::span<const geo::TileKey> quads,
                              std::span<const uint64_t> triangles, const geo::GeoBox& extent,
                              QuadSplit split, int ranks);

// The part of a selected quad's triangles that a rank draws: `count` from
// `first`, in the order of the quad's mesh (count 0: none of them).
struct TriangleRange {
  uint64_t first = 0;
  uint64_t count = 0;
  friend bool operator==(const TriangleRange&, const TriangleRange&) = default;
};

// The triangles of each quad that `rank` draws. Block and quadtree give every
// quad whole to one rank (assign_quads), and so does active unless
// `split_quads`: then the quads' triangles, in quadtree order, are cut into
// `ranks` runs of equal length (to one triangle), and a quad on a cut is
// drawn in part by each rank it straddles. A mesh whose quads are ranges of
// one index buffer (edge marks) can be split so; a few large quads then no
// longer limit the balance.
std::vector<TriangleRange> rank_triangles(std::span<const geo::TileKey> quads,
                                          std::span<const uint64_t> triangles,
                                          const geo::GeoBox& extent, QuadSplit split, int ranks,
                                          int rank, bool split_quads);

// Load imbalance of per-rank work: max / mean - 1 (0 for a perfect balance).
double imbalance(std::span<const uint64_t> per_rank);

}  // namespace relief::parallel
