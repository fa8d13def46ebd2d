#include "relief/tiles/geometric_error.h"

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "full_mesh_cell.h"
#include "relief/base/file_io.h"
#include "relief/base/first_error.h"
#include "relief/base/lru_cache.h"
#include "relief/tiles/store.h"
#include "relief/tiles/store_layout.h"
#include "relief/tiles/tile_file.h"

namespace relief::tiles {
namespace {

using geo::TileKey;

// Min and max of a finest tile's valid samples over aligned blocks of
// 2^k x 2^k samples, k = 0 .. log2(height): the range of the samples under an
// ancestor's cell without visiting them. An empty block is {+inf, -inf}.
class BlockRanges {
 public:
  BlockRanges(const Raster& fine, int border, int w, int h) {
    const auto values = fine.f32();
    const auto stride = static_cast<size_t>(fine.width());
    Level base{w, h, std::vector<float>(static_cast<size_t>(w) * static_cast<size_t>(h)), {}};
    base.hi.resize(base.lo.size());
    for (int j = 0; j < h; ++j) {
      for (int i = 0; i < w; ++i) {
        const float v =
            values[static_cast<size_t>(j + border) * stride + static_cast<size_t>(i + border)];
        const size_t at = static_cast<size_t>(j) * static_cast<size_t>(w) + static_cast<size_t>(i);
        base.lo[at] = std::isnan(v) ? kInf : v;
        base.hi[at] = std::isnan(v) ? -kInf : v;
      }
    }
    levels_.push_back(std::move(base));
    while (levels_.back().h > 1) {
      const Level& in = levels_.back();
      Level out{in.w / 2, in.h / 2, {}, {}};
      out.lo.resize(static_cast<size_t>(out.w) * static_cast<size_t>(out.h));
      out.hi.resize(out.lo.size());
      for (int j = 0; j < out.h; ++j) {
        for (int i = 0; i < out.w; ++i) {
          const size_t a =
              static_cast<size_t>(2 * j) * static_cast<size_t>(in.w) + static_cast<size_t>(2 * i);
          const size_t b = a + static_cast<size_t>(in.w);
          const size_t at =
              static_cast<size_t>(j) * static_cast<size_t>(out.w) + static_cast<size_t>(i);
          out.lo[at] = std::min({in.lo[a], in.lo[a + 1], in.lo[b], in.lo[b + 1]});
          out.hi[at] = std::max({in.hi[a], in.hi[a + 1], in.hi[b], in.hi[b + 1]});
        }
      }
      levels_.push_back(std::move(out));
    }
  }
  // The range of block (i, j) of size 2^k; beyond the last level, the whole tile's.
  std::pair<float, float> at(int k, int64_t i, int64_t j) const {
    if (k >= static_cast<int>(levels_.size())) {
      const Level& top = levels_.back();
      return {*std::min_element(top.lo.begin(), top.lo.end()),
              *std::max_element(top.hi.begin(), top.hi.end())};
    }
    const Level& l = levels_[static_cast<size_t>(k)];
    const size_t p = static_cast<size_t>(j) * static_cast<size_t>(l.w) + static_cast<size_t>(i);
    return {l.lo[p], l.hi[p]};
  }

 private:
  static constexpr float kInf = std::numeric_limits<float>::infinity();
  struct Level {
    int w, h;
    std::vector<float> lo, hi;
  };
  std::vector<Level> levels_;
};

// Raises `worst` to the largest distance between the ancestor's full mesh and
// the finest tile's samples, m levels below it. Positions are in finest sample
// units relative to the ancestor's corner (gx, gy), so the ancestor's cell of a
// sample is gx >> m and its offset in the cell (gx - ci 2^m + 0.5) 2^-m,
// exactly the u that full_mesh_height computes from x = (gx + 0.5) 2^-m.
// A cell whose mesh and samples cannot be further apart than `worst` (their
// height ranges say so) is skipped: it cannot change the maximum.
void raise_deviation(const Raster& fine, int fine_border, const BlockRanges& ranges,
                     const Raster& ancestor, const TileShape& shape, const TileKey& f,
                     const TileKey& a, int m, std::vector<double>& us, std::vector<float>& corners,
                     double& worst_out) {
  double worst = worst_out;  // in a register, not stored through the reference per sample
  const int border = shape.border;
  const int w = shape.width - 2 * border, h = shape.height - 2 * border;
  const int64_t gx0 = static_cast<int64_t>(f.x - (a.x << m)) * w;
  const int64_t gy0 = static_cast<int64_t>(f.y - (a.y << m)) * h;
  const double unit = std::ldexp(1.0, -m);
  us.resize(static_cast<size_t>(w));
  for (int64_t gx = gx0; gx < gx0 + w; ++gx) {
    us[static_cast<size_t>(gx - gx0)] = (static_cast<double>(gx - ((gx >> m) << m)) + 0.5) * unit;
  }
  const auto values = fine.f32();
  const auto stride = static_cast<size_t>(fine.width());
  // The corners of the ancestor's cells over this tile, each computed once.
  const int64_t ci0 = gx0 >> m, cj0 = gy0 >> m;
  const int nx = static_cast<int>(((gx0 + w - 1) >> m) - ci0) + 1;
  const int ny = static_cast<int>(((gy0 + h - 1) >> m) - cj0) + 1;
  corners.resize(static_cast<size_t>(nx + 1) * static_cast<size_t>(ny + 1));
  for (int y = 0; y <= ny; ++y) {
    for (int x = 0; x <= nx; ++x) {
      corners[static_cast<size_t>(y) * static_cast<size_t>(nx + 1) + static_cast<size_t>(x)] =
          corner_height(ancestor, border, static_cast<int>(ci0) + x, static_cast<int>(cj0) + y);
    }
  }
  const auto centres = ancestor.f32();
  const auto centre_stride = static_cast<size_t>(ancestor.width());
  for (int y = 0; y < ny; ++y) {
    for (int x = 0; x < nx; ++x) {
      const int64_t ci = ci0 + x, cj = cj0 + y;
      const auto i = static_cast<int>(ci), j = static_cast<int>(cj);
      const float* k =
          &corners[static_cast<size_t>(y) * static_cast<size_t>(nx + 1) + static_cast<size_t>(x)];
      const float* k1 = k + nx + 1;
      const MeshCell cell =
          make_cell(centres[static_cast<size_t>(j + border) * centre_stride +
                            static_cast<size_t>(i + border)],
                    k[0], k[1], k1[0], k1[1], stencil_inside(ancestor, border, i, j));
      if (!cell.valid) continue;  // the fall-off at the data's edge or a void
      if (m == 1) {
        // The parent's cell over exactly 2 x 2 samples, at u, v of 1/4 and
        // 3/4 (gx0 and gy0 are even): the general loop below with its
        // positions and triangles known (cell_triangle: 0, 0, 2, 1), the same
        // operations in the same order. Half the cells of the whole pass.
        const float* top = values.data() + static_cast<size_t>(2 * y + fine_border) * stride +
                           static_cast<size_t>(2 * x + fine_border);
        const float* bottom = top + stride;
        auto distance = [](double row, double b, double u, float value) {
          return std::isnan(value) ? 0.0 : std::abs(row + b * u - value);
        };
        const double row0 = cell.a[0] + cell.c[0] * 0.25;
        const double row1 = cell.a[1] + cell.c[1] * 0.75;
        const double row2 = cell.a[2] + cell.c[2] * 0.75;
        worst = std::max(worst, std::max(distance(row0, cell.b[0], 0.25, top[0]),
                                         distance(row0, cell.b[0], 0.75, top[1])));
        worst = std::max(worst, std::max(distance(row2, cell.b[2], 0.25, bottom[0]),
                                         distance(row1, cell.b[1], 0.75, bottom[1])));
        continue;
      }
      // A cell of 2 x 2 samples costs about what its test would.
      if (m > 1) {
        const auto [lo, hi] = ranges.at(m, x, y);
        const double bound = std::max(cell.hi - lo, hi - cell.lo);
        // Margin for the rounding of the mesh's heights inside the cell.
        const double slack = 1e-9 * (1 + std::abs(cell.lo) + std::abs(cell.hi));
        if (bound + slack < worst) continue;
      }
      const int64_t ya = std::max(gy0, cj << m), yb = std::min(gy0 + h, (cj + 1) << m);
      const int64_t xa = std::max(gx0, ci << m), xb = std::min(gx0 + w, (ci + 1) << m);
      for (int64_t gy = ya; gy < yb; ++gy) {
        const double v = (static_cast<double>(gy - (cj << m)) + 0.5) * unit;
        // cell_height's terms, the row's part first as it adds them.
        double row[4];
        for (int t = 0; t < 4; ++t) row[t] = cell.a[t] + cell.c[t] * v;
        const float* line = values.data() + static_cast<size_t>(gy - gy0 + fine_border) * stride +
                            static_cast<size_t>(fine_border);
        // A nodata sample (NaN) counts as a distance of 0.
        auto distance = [&](int64_t gx) {
          const double u = us[static_cast<size_t>(gx - gx0)];
          const int t = cell_triangle(u, v);
          const float value = line[gx - gx0];
          return std::isnan(value) ? 0.0 : std::abs(row[t] + cell.b[t] * u - value);
        };
        // Two samples at a time: half as long a chain of dependent maxima.
        int64_t gx = xa;
        for (; gx + 1 < xb; gx += 2)
          worst = std::max(worst, std::max(distance(gx), distance(gx + 1)));
        if (gx < xb) worst = std::max(worst, distance(gx));
      }
    }
  }
  worst_out = worst;
}

// Non-negative floats order like their bit patterns: a lock-free maximum.
void raise_to(std::atomic<uint32_t>& slot, float value) {
  const uint32_t bits = std::bit_cast<uint32_t>(value);
  uint32_t seen = slot.load(std::memory_order_relaxed);
  while (bits > seen && !slot.compare_exchange_weak(seen, bits, std::memory_order_relaxed)) {
  }
}

}  // namespace

float round_up_to_float(double distance) {
  float f = static_cast<float>(distance);
  if (static_cast<double>(f) < distance)
    f = std::nextafter(f, std::numeric_limits<float>::infinity());
  return f;
}

uint64_t ancestor_cache_bytes(const TileShape& shape, size_t levels, unsigned workers) {
  return shape.raster_bytes() * levels * (uint64_t{workers} + 1);
}

Status compute_geometric_errors(std::span<LevelIndex> indices, const TileShape& shape,
                                const BorderedTileReader& read, Executor& executor,
                                Progress& progress, const BorderedTileReader& read_interior) {
  if (indices.empty()) return {};
  const int finest = indices.back().level();
  // One slot per entry, in entries() order (sorting here, before the workers
  // call find() concurrently).
  std::vector<std::unique_ptr<std::atomic<uint32_t>[]>> worst;
  for (const LevelIndex& index : indices) {
    worst.push_back(std::make_unique<std::atomic<uint32_t>[]>(index.entries().size()));
  }
  std::vector<TileKey> keys;
  for (const IndexEntry& e : indices.back().entries()) keys.push_back(e.key);
  std::sort(keys.begin(), keys.end(),
            [](const TileKey& a, const TileKey& b) { return a.morton() < b.morton(); });

  // Workers walk neighbouring finest tiles, which share their ancestors: a
  // few tiles per level and worker are enough for each to be decoded once.
  const uint64_t budget = ancestor_cache_bytes(shape, indices.size(), executor.concurrency());
  LruCache<TileKey, Raster, geo::TileKeyHash> ancestors(
      budget, [](const Raster& r) { return r.byte_size(); });
  auto ancestor = [&](const TileKey& key) -> Result<std::shared_ptr<const Raster>> {
    if (auto hit = ancestors.get(key)) return hit;
    auto tile = RELIEF_TRY(read(key));
    if (tile) ancestors.put(key, tile);
    return tile;
  };
  auto errors_below = [&](const TileKey& f) -> Status {
    const auto fine = RELIEF_TRY(read_interior ? read_interior(f) : read(f));
    if (!fine) return {};
    const int fine_border = read_interior ? 0 : shape.border;
    const BlockRanges ranges(*fine, fine_border, shape.width - 2 * shape.border,
                             shape.height - 2 * shape.border);
    std::vector<double> us;
    std::vector<float> corners;
    for (size_t l = 0; l + 1 < indices.size(); ++l) {
      const int m = finest - indices[l].level();
      const TileKey a{indices[l].level(), f.x >> m, f.y >> m};
      const IndexEntry* entry = indices[l].find(a);
      if (!entry) continue;
      const auto tile = RELIEF_TRY(ancestor(a));
      if (!tile) continue;
      std::atomic<uint32_t>& slot =
          worst[l][static_cast<size_t>(entry - indices[l].entries().data())];
      // Starting from what other finest tiles found lets more cells be skipped.
      double local = std::bit_cast<float>(slot.load(std::memory_order_relaxed));
      raise_deviation(*fine, fine_border, ranges, *tile, shape, f, a, m, us, corners, local);
      raise_to(slot, round_up_to_float(local));
    }
    return {};
  };
  FirstError error;
  progress.begin("geometric errors", keys.size());
  executor.parallel_for(keys.size(), [&](size_t k) {
    if (!error.failed()) {
      if (auto st = errors_below(keys[k]); !st) error.set(st.error());
    }
    progress.advance();
  });
  progress.end();
  RELIEF_CHECK(error.status());
  for (size_t l = 0; l < indices.size(); ++l) {
    const auto entries = indices[l].entries();  // a copy: set_error edits them
    for (size_t i = 0; i < entries.size(); ++i) {
      indices[l].set_error(entries[i].key, std::bit_cast<float>(worst[l][i].load()));
    }
  }
  return {};
}

BorderedTileReader store_tile_reader(const Store& store) {
  return [&store](const TileKey& key) -> Result<std::shared_ptr<const Raster>> {
    Tile tile = RELIEF_TRY(store.read_tile(key));
    if (tile.raster.type() != SampleType::Float32) {
      return fail(fmt::format("{}: not an elevation store", store.root().string()));
    }
    return std::make_shared<const Raster>(std::move(tile.raster));
  };
}

BorderedTileReader directory_tile_reader(const std::filesystem::path& root,
                                         const TileShape& shape) {
  return [root, shape](const TileKey& key) -> Result<std::shared_ptr<const Raster>> {
    const std::filesystem::path path = root / tile_relative_path(key);
    const auto bytes = RELIEF_TRY(read_file(path, max_tile_file_bytes(shape)));
    Tile tile = RELIEF_TRY(decode_tile(bytes, path.string(), shape));
    return std::make_shared<const Raster>(std::move(tile.raster));
  };
}

}  // namespace relief::tiles
