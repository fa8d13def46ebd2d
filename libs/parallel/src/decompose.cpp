#include "relief/parallel/decompose.h"

#include <algorithm>
#include <cmath>
#include <numeric>

#include <fmt/format.h>

namespace relief::parallel {

namespace {

// Where a quad's centre lies in the store's extent, both in [0, 1].
std::pair<double, double> position_in(const geo::TileKey& key, const geo::GeoBox& extent) {
  const geo::GeoBox b = key.bounds();
  const double u = ((b.west + b.east) / 2 - extent.west) / extent.width();
  const double v = (extent.north - (b.north + b.south) / 2) / extent.height();
  return {std::clamp(u, 0.0, 1.0), std::clamp(v, 0.0, 1.0)};
}

// The quad's place in a quadtree (Morton) enumeration of the extent: 16
// levels below it, interleaved.
uint32_t quadtree_index(const geo::TileKey& key, const geo::GeoBox& extent) {
  const auto [u, v] = position_in(key, extent);
  const uint32_t x = std::min(uint32_t{65535}, static_cast<uint32_t>(u * 65536));
  const uint32_t y = std::min(uint32_t{65535}, static_cast<uint32_t>(v * 65536));
  uint32_t code = 0;
  for (int bit = 0; bit < 16; ++bit) {
    code |= ((x >> bit) & 1u) << (2 * bit);
    code |= ((y >> bit) & 1u) << (2 * bit + 1);
  }
  return code;
}

// The quads' indices in quadtree order: coherent pieces of terrain per rank.
std::vector<size_t> quadtree_order(std::span<const geo::TileKey> quads, const geo::GeoBox& extent) {
  std::vector<size_t> order(quads.size());
  std::iota(order.begin(), order.end(), size_t{0});
  std::vector<uint32_t> code(quads.size());
  for (size_t i = 0; i < quads.size(); ++i) code[i] = quadtree_index(quads[i], extent);
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) {
    return std::tie(code[a], quads[a]) < std::tie(code[b], quads[b]);
  });
  return order;
}

int range_of(double position, int ranks) {
  return std::clamp(static_cast<int>(position * ranks), 0, ranks - 1);
}

}  // namespace

Result<ParallelMode> parse_parallel_mode(std::string_view text) {
  ParallelMode m;
  const std::string_view first = "sort-first:", last = "sort-last:", wall = "wall:";
  if (text.starts_with(first)) {
    m.kind = ParallelMode::Kind::sort_first;
    const std::string_view s = text.substr(first.size());
    if (s == "h") {
      m.screen = ScreenSplit::horizontal;
    } else if (s == "v") {
      m.screen = ScreenSplit::vertical;
    } else if (s == "grid") {
      m.screen = ScreenSplit::grid;
    } else {
      return fail(fmt::format("--parallel: '{}' is not sort-first:h, :v or :grid", text));
    }
  } else if (text.starts_with(last)) {
    m.kind = ParallelMode::Kind::sort_last;
    const std::string_view s = text.substr(last.size());
    if (s == "block") {
      m.quads = QuadSplit::block;
    } else if (s == "quadtree") {
      m.quads = QuadSplit::quadtree;
    } else if (s == "active") {
      m.quads = QuadSplit::active;
    } else {
      return fail(
          fmt::format("--parallel: '{}' is not sort-last:block, :quadtree or :active", text));
    }
  } else if (text.starts_with(wall) && text.size() > wall.size()) {
    m.kind = ParallelMode::Kind::wall;
    m.wall_file = std::string(text.substr(wall.size()));
  } else {
    return fail(fmt::format(
        "--parallel: '{}' is not sort-first:h|v|grid, sort-last:block|quadtree|active or "
        "wall:FILE.json",
        text));
  }
  return m;
}

std::string to_string(const ParallelMode& m) {
  switch (m.kind) {
    case ParallelMode::Kind::sort_first:
      return std::string("sort-first:") + (m.screen == ScreenSplit::horizontal ? "h"
                                           : m.screen == ScreenSplit::vertical ? "v"
                                                                               : "grid");
    case ParallelMode::Kind::sort_last:
      return std::string("sort-last:") + (m.quads == QuadSplit::block      ? "block"
                                          : m.quads == QuadSplit::quadtree ? "quadtree"
                                                                           : "active");
    case ParallelMode::Kind::wall:
      return "wall:" + m.wall_file;
  }
  return {};
}

std::vector<lod::PixelRect> screen_tiles(int width, int height, ScreenSplit split, int ranks) {
  int columns = 1, rows = 1;
  if (split == ScreenSplit::horizontal) rows = ranks;
  if (split == ScreenSplit::vertical) columns = ranks;
  if (split == ScreenSplit::grid) {
    // The factorisation whose tiles are nearest to square.
    double best = INFINITY;
    for (int c = 1; c <= ranks; ++c) {
      if (ranks % c) continue;
      const double aspect = (double(width) / c) / (double(height) / (ranks / c));
      if (std::abs(std::log(aspect)) < best) best = std::abs(std::log(aspect)), columns = c;
    }
    rows = ranks / columns;
  }
  std::vector<lod::PixelRect> tiles;
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < columns; ++c) {
      const int x0 = width * c / columns, x1 = width * (c + 1) / columns;
      const int y0 = height * r / rows, y1 = height * (r + 1) / rows;
      tiles.push_back({x0, y0, x1 - x0, y1 - y0});
    }
  }
  return tiles;
}

std::vector<int> assign_quads(std::span<const geo::TileKey> quads,
                              std::span<const uint64_t> triangles, const geo::GeoBox& extent,
                              QuadSplit split, int ranks) {
  std::vector<int> owner(quads.size(), 0);
  if (ranks <= 1) return owner;
  if (split == QuadSplit::block) {
    for (size_t i = 0; i < quads.size(); ++i) {
      owner[i] = range_of(position_in(quads[i], extent).first, ranks);
    }
    return owner;
  }
  if (split == QuadSplit::quadtree) {
    for (size_t i = 0; i < quads.size(); ++i) {
      owner[i] = range_of(quadtree_index(quads[i], extent) / 4294967296.0, ranks);
    }
    return owner;
  }
  // Active patches whole: each quad goes where the middle of its triangles
  // falls in the quadtree-ordered run (rank_triangles without splitting).
  const std::vector<size_t> order = quadtree_order(quads, extent);
  const double total =
      static_cast<double>(std::accumulate(triangles.begin(), triangles.end(), uint64_t{0}));
  double before = 0;
  for (size_t i : order) {
    const double t = static_cast<double>(triangles[i]);
    owner[i] = total > 0 ? range_of((before + t / 2) / total, ranks) : 0;
    before += t;
  }
  return owner;
}

std::vector<TriangleRange> rank_triangles(std::span<const geo::TileKey> quads,
                                          std::span<const uint64_t> triangles,
                                          const geo::GeoBox& extent, QuadSplit split, int ranks,
                                          int rank, bool split_quads) {
  std::vector<TriangleRange> mine(quads.size());
  if (split != QuadSplit::active || !split_quads || ranks <= 1) {
    const std::vector<int> owner = assign_quads(quads, triangles, extent, split, ranks);
    for (size_t i = 0; i < quads.size(); ++i) {
      if (owner[i] == rank) mine[i] = {0, triangles[i]};
    }
    return mine;
  }
  // The quadtree-ordered run of every triangle, cut at total * r / ranks:
  // rank r draws [begin, end) of it, the quads on a cut in part.
  const uint64_t total = std::accumulate(triangles.begin(), triangles.end(), uint64_t{0});
  const auto cut = [&](int r) {
    return static_cast<uint64_t>(
        (static_cast<unsigned __int128>(total) * static_cast<unsigned>(r)) /
        static_cast<unsigned>(ranks));
  };
  const uint64_t begin = cut(rank), end = cut(rank + 1);
  uint64_t before = 0;
  for (size_t i : quadtree_order(quads, extent)) {
    const uint64_t lo = std::max(before, begin), hi = std::min(before + triangles[i], end);
    if (lo < hi) mine[i] = {lo - before, hi - lo};
    before += triangles[i];
  }
  return mine;
}

double imbalance(std::span<const uint64_t> per_rank) {
  if (per_rank.empty()) return 0;
  const double sum =
      static_cast<double>(std::accumulate(per_rank.begin(), per_rank.end(), uint64_t{0}));
  const double mean = sum / static_cast<double>(per_rank.size());
  const uint64_t max = *std::max_element(per_rank.begin(), per_rank.end());
  return mean > 0 ? static_cast<double>(max) / mean - 1 : 0;
}

}  // namespace relief::parallel
