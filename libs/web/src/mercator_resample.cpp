#include "mercator_resample.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <limits>
#include <numbers>

#include <fmt/format.h>

namespace relief::web {
namespace {

// Samples [c0, c0 + width) x [r0, r0 + height) of one level in global
// coordinates (columns not wrapped); nodata outside.
template <class Sample>
struct Window {
  int64_t c0 = 0, r0 = 0, width = 0, height = 0;
  std::vector<Sample> values;
  Sample none{};
  Sample at(int64_t c, int64_t r) const {
    if (c < c0 || r < r0 || c >= c0 + width || r >= r0 + height) return none;
    return values[static_cast<size_t>((r - r0) * width + (c - c0))];
  }
};

// Inclusive sample indices [first, last] of a level; empty when first > last.
struct Span {
  int64_t first = 0, last = -1;
};

Span intersect(Span a, Span b) {
  return {std::max(a.first, b.first), std::min(a.last, b.last)};
}

// The samples whose cells meet [lo, hi) along one axis, positions counted in
// samples from the level's west (or north) edge.
Span cells_meeting(double lo, double hi) {
  return {static_cast<int64_t>(std::floor(lo)), static_cast<int64_t>(std::ceil(hi)) - 1};
}

template <class Sample>
Result<Window<Sample>> read_window(const BlockReader<Sample>& blocks, const ResampleSource& source,
                                   int level, double spacing, Span columns, Span rows,
                                   Sample none) {
  const geo::GeoBox& data = source.data;
  // A box around the whole world wraps: every column, the antimeridian's too.
  if (data.width() < 360.0) {
    columns =
        intersect(columns, cells_meeting((data.west + 180) / spacing, (data.east + 180) / spacing));
  }
  rows = intersect(rows, cells_meeting((90 - data.north) / spacing, (90 - data.south) / spacing));
  Window<Sample> w;
  w.none = none;
  if (columns.first > columns.last || rows.first > rows.last) return w;
  w.c0 = columns.first, w.r0 = rows.first;
  w.width = columns.last - columns.first + 1, w.height = rows.last - rows.first + 1;
  // At most 2^e samples a pixel when the rule's level is read (e the extra
  // levels of high latitudes, 3 at 85°); far more only when a store whose
  // min level is above the rule's is read at a small zoom.
  constexpr int64_t kMaxSamples = int64_t{1} << 26;
  if (w.width * w.height > kMaxSamples) {
    return fail(
        fmt::format("level {}: {} x {} samples for one web tile; the store's min level "
                    "is too fine for this zoom",
                    level, w.width, w.height));
  }
  w.values = RELIEF_TRY(
      blocks.read(level, w.c0, w.r0, static_cast<int>(w.width), static_cast<int>(w.height)));
  return w;
}

// Runs of pixel rows that read one level, each read as one window.
template <class Sample, class Out, class Blend>
Result<std::vector<Out>> resample(const BlockReader<Sample>& blocks, const ResampleSource& source,
                                  const XyzKey& key, int n, Sample none, Blend blend) {
  std::vector<double> lon(static_cast<size_t>(n)), lat(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) {
    lon[static_cast<size_t>(i)] = pixel_lon(key, n, i);
    lat[static_cast<size_t>(i)] = pixel_lat(key, n, i);
  }
  std::vector<Out> out(static_cast<size_t>(n) * static_cast<size_t>(n));
  std::vector<double> fx(static_cast<size_t>(n));
  for (int j0 = 0; j0 < n;) {
    const int level = source_level(source, key.z, n, lat[static_cast<size_t>(j0)]);
    int j1 = j0 + 1;
    while (j1 < n && source_level(source, key.z, n, lat[static_cast<size_t>(j1)]) == level) ++j1;
    // Continuous sample coordinates: (0, 0) is the centre of the level's
    // north-west sample.
    const double d = 180.0 / std::ldexp(1.0, level + source.log2_tile_height);
    for (size_t i = 0; i < fx.size(); ++i) fx[i] = (lon[i] + 180) / d - 0.5;
    const auto fy = [&](int j) { return (90 - lat[static_cast<size_t>(j)]) / d - 0.5; };
    const Span columns{static_cast<int64_t>(std::floor(fx.front())),
                       static_cast<int64_t>(std::floor(fx.back())) + 1};
    const Span rows{static_cast<int64_t>(std::floor(fy(j0))),
                    static_cast<int64_t>(std::floor(fy(j1 - 1))) + 1};
    const Window<Sample> w = RELIEF_TRY(read_window(blocks, source, level, d, columns, rows, none));
    for (int j = j0; j < j1; ++j) {
      const double y = fy(j), y0 = std::floor(y), ty = y - y0;
      const auto r = static_cast<int64_t>(y0);
      Out* row = out.data() + static_cast<size_t>(j) * static_cast<size_t>(n);
      for (size_t i = 0; i < fx.size(); ++i) {
        const double x0 = std::floor(fx[i]), tx = fx[i] - x0;
        const auto c = static_cast<int64_t>(x0);
        const std::array<Sample, 4> s{w.at(c, r), w.at(c + 1, r), w.at(c, r + 1),
                                      w.at(c + 1, r + 1)};
        const std::array<double, 4> weight{(1 - tx) * (1 - ty), tx * (1 - ty), (1 - tx) * ty,
                                           tx * ty};
        row[i] = blend(s, weight);
      }
    }
    j0 = j1;
  }
  return out;
}

double blend_heights(const std::array<float, 4>& h, const std::array<double, 4>& weight) {
  double sum = 0, total = 0;
  for (size_t k = 0; k < 4; ++k) {
    if (std::isnan(h[k])) continue;
    sum += weight[k] * h[k];
    total += weight[k];
  }
  return total > 0 ? sum / total : std::numeric_limits<double>::quiet_NaN();
}

Rgba blend_pixels(const std::array<Rgba, 4>& p, const std::array<double, 4>& weight) {
  double alpha = 0;
  std::array<double, 3> colour{};
  for (size_t k = 0; k < 4; ++k) {
    const double w = weight[k] * p[k][3];
    alpha += w;
    for (size_t c = 0; c < 3; ++c) colour[c] += w * p[k][c];
  }
  if (alpha <= 0) return Rgba{};
  const auto byte = [](double v) {
    return static_cast<uint8_t>(std::clamp(std::round(v), 0.0, 255.0));
  };
  return {byte(colour[0] / alpha), byte(colour[1] / alpha), byte(colour[2] / alpha), byte(alpha)};
}

}  // namespace

int source_level(const ResampleSource& source, int z, int tile_size, double lat) {
  // Level L0 = z + log2(N) - (k + 1) has the spacing of a pixel's width in
  // longitude. A Mercator pixel spans cos(lat) of that in latitude, so
  // floor(log2(1 / cos(lat))) levels finer keep the samples' north-south
  // spacing within [1, 2) pixels (none skipped between pixel centres, and
  // no detail lost to a coarser level); east-west, where samples are
  // narrower on the ground by cos(lat), within [cos(lat), 2 cos(lat)).
  const int log2_size = std::countr_zero(static_cast<unsigned>(tile_size));
  const double c = std::cos(lat * std::numbers::pi / 180);
  const int finer = static_cast<int>(std::floor(-std::log2(c)));
  return std::clamp(z + log2_size - (source.log2_tile_height + 1) + finer, source.min_level,
                    source.max_level);
}

Result<std::vector<double>> resample_heights(const SampleBlocks& blocks,
                                             const ResampleSource& source, const XyzKey& key,
                                             int tile_size) {
  return resample<float, double>(blocks, source, key, tile_size,
                                 std::numeric_limits<float>::quiet_NaN(), blend_heights);
}

Result<std::vector<Rgba>> resample_pixels(const PixelBlocks& blocks, const ResampleSource& source,
                                          const XyzKey& key, int tile_size) {
  return resample<Rgba, Rgba>(blocks, source, key, tile_size, Rgba{}, blend_pixels);
}

}  // namespace relief::web
