#include "relief/web/terrain_tiler.h"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "availability.h"
#include "relief/tiles/store.h"
#include "relief/web/quantized_mesh.h"
#include "relief/web/rtin.h"
#include "sample_block.h"

namespace relief::web {
namespace {

constexpr int kLog2Cells = 8;  // 256 x 256 samples a tile
constexpr int kCells = 1 << kLog2Cells;
constexpr int kCorners = kCells + 1;  // the lattice's points per side

// Cell corners (p, q) = global corners (corner0 + p, row0 + q) of a level:
// each the mean of the 4 samples around it, with the float operations of
// the renderer's bilinear lookup where all 4 are data; where some are
// nodata, the mean of the others; 0 m (the ellipsoid) where none is.
struct Lattice {
  int size = 0;
  std::vector<float> heights;
  float at(int p, int q) const {
    return heights[static_cast<size_t>(q) * static_cast<size_t>(size) + static_cast<size_t>(p)];
  }
};

float corner_of(float a, float b, float c, float d) {
  if (!std::isnan(a) && !std::isnan(b) && !std::isnan(c) && !std::isnan(d)) {
    const float f = 0.5f;
    const float top = a + (b - a) * f, bottom = c + (d - c) * f;
    return top + (bottom - top) * f;
  }
  float sum = 0;
  int count = 0;
  for (const float v : {a, b, c, d}) {
    if (!std::isnan(v)) sum += v, ++count;
  }
  return count ? sum / static_cast<float>(count) : 0.0f;
}

Result<Lattice> read_lattice(const SampleBlocks& blocks, int level, int64_t corner0, int64_t row0,
                             int size) {
  const int samples = size + 1;
  const auto s = RELIEF_TRY(blocks.read(level, corner0 - 1, row0 - 1, samples, samples));
  Lattice lattice{size, std::vector<float>(static_cast<size_t>(size) * static_cast<size_t>(size))};
  const auto at = [&](int i, int j) {
    return s[static_cast<size_t>(j) * static_cast<size_t>(samples) + static_cast<size_t>(i)];
  };
  for (int q = 0; q < size; ++q) {
    for (int p = 0; p < size; ++p) {
      lattice.heights[static_cast<size_t>(q) * static_cast<size_t>(size) + static_cast<size_t>(p)] =
          corner_of(at(p, q), at(p + 1, q), at(p, q + 1), at(p + 1, q + 1));
    }
  }
  return lattice;
}

// Positions of lattice points in ECEF from per-column and per-row tables.
class LatticeGeometry {
 public:
  LatticeGeometry(double west, double north, double spacing, int size) {
    for (int i = 0; i < size; ++i) {
      const double lon = geo::degrees_to_radians(west + i * spacing);
      const double lat = geo::degrees_to_radians(std::clamp(north - i * spacing, -90.0, 90.0));
      cos_lon_.push_back(std::cos(lon)), sin_lon_.push_back(std::sin(lon));
      cos_lat_.push_back(std::cos(lat)), sin_lat_.push_back(std::sin(lat));
    }
  }
  geo::Ecef at(int p, int q, double h) const {
    const double n = geo::wgs84::prime_vertical_radius(sin_lat_[q]);
    const double r = (n + h) * cos_lat_[q];
    return {r * cos_lon_[p], r * sin_lon_[p],
            (n * (1 - geo::wgs84::kFirstEccentricitySquared) + h) * sin_lat_[q]};
  }
  geo::Ecef up(int p, int q) const {
    return {cos_lat_[q] * cos_lon_[p], cos_lat_[q] * sin_lon_[p], sin_lat_[q]};
  }

 private:
  std::vector<double> cos_lon_, sin_lon_, cos_lat_, sin_lat_;
};

geo::Ecef minus(const geo::Ecef& a, const geo::Ecef& b) {
  return {a.x - b.x, a.y - b.y, a.z - b.z};
}

}  // namespace

geo::GeoBox TerrainKey::bounds() const {
  const double size = 180.0 / std::ldexp(1.0, level);
  return {-180 + x * size, -90 + y * size, -180 + (x + 1) * size, -90 + (y + 1) * size};
}

std::string TerrainKey::to_string() const {
  return fmt::format("{}/{}/{}", level, x, y);
}

struct TerrainTiler::Impl {
  std::shared_ptr<const tiles::Store> store;
  TerrainOptions options;
  SampleBlocks blocks;
  Rtin rtin{kLog2Cells};
  int max_level = 0;

  Impl(std::shared_ptr<const tiles::Store> s, TerrainOptions o)
      : store(s), options(std::move(o)), blocks(std::move(s), options.cache_bytes) {}

  geo::TileKey quad_of(const TerrainKey& k) const {
    return {k.level, k.x >> 1, (1u << k.level) - 1 - k.y};
  }
  bool meets_bbox(const TerrainKey& k) const { return meets(k, options.bbox); }

  // The errors of a tile's lattice alone, kept for its neighbours: each
  // tile's are needed by itself and its 4 neighbours.
  mutable LruCache<TerrainKey, std::vector<float>, TerrainKeyHash> plain_cache{
      uint64_t{32} << 20, [](const std::vector<float>& v) { return v.size() * sizeof(float); }};

  Result<std::shared_ptr<const std::vector<float>>> plain_errors(const TerrainKey& key) const {
    if (auto hit = plain_cache.get(key)) return hit;
    const int64_t rows = int64_t{kCells} << key.level;
    const Lattice l = RELIEF_TRY(read_lattice(blocks, key.level, int64_t{key.x} * kCells,
                                              rows - (int64_t{key.y} + 1) * kCells, kCorners));
    auto errors = std::make_shared<std::vector<float>>(l.heights.size(), 0.0f);
    rtin.accumulate_errors(l.heights, *errors);
    plain_cache.put(key, errors);
    return std::shared_ptr<const std::vector<float>>(std::move(errors));
  }

  float max_error(int level) const {
    if (options.max_error) return *options.max_error;
    const double e = cesium_level_error(level);
    return static_cast<float>(level == store->manifest().max_level ? e / 8 : e);
  }

  Result<std::vector<std::byte>> tile(const TerrainKey& key) const;
};

Result<std::vector<std::byte>> TerrainTiler::Impl::tile(const TerrainKey& key) const {
  const int level = key.level;
  const int64_t rows = int64_t{kCells} << level;
  const int64_t corner0 = int64_t{key.x} * kCells;
  const int64_t row0 = rows - (int64_t{key.y} + 1) * kCells;  // from the north pole
  // The lattice with one more point on every side, for the normals.
  const Lattice wide = RELIEF_TRY(read_lattice(blocks, level, corner0 - 1, row0 - 1, kCorners + 2));

  // Raise each edge point to the neighbour's error there: both tiles then
  // hold max(own side, other side) at every point of their shared edge, so
  // both cut it alike.
  std::vector<float> errors = *RELIEF_TRY(plain_errors(key));
  const auto at = [&](int p, int q) -> float& {
    return errors[static_cast<size_t>(q) * kCorners + p];
  };
  const auto edge = [](const std::vector<float>& e, int p, int q) {
    return e[static_cast<size_t>(q) * kCorners + p];
  };
  const uint32_t columns = 2u << level;
  {
    const auto west = RELIEF_TRY(plain_errors({level, (key.x + columns - 1) % columns, key.y}));
    const auto east = RELIEF_TRY(plain_errors({level, (key.x + 1) % columns, key.y}));
    for (int q = 0; q < kCorners; ++q) {
      at(0, q) = std::max(at(0, q), edge(*west, kCells, q));
      at(kCells, q) = std::max(at(kCells, q), edge(*east, 0, q));
    }
  }
  if (key.y + 1 < (1u << level)) {
    const auto north = RELIEF_TRY(plain_errors({level, key.x, key.y + 1}));
    for (int p = 0; p < kCorners; ++p) at(p, 0) = std::max(at(p, 0), edge(*north, p, kCells));
  }
  if (key.y > 0) {
    const auto south = RELIEF_TRY(plain_errors({level, key.x, key.y - 1}));
    for (int p = 0; p < kCorners; ++p) at(p, kCells) = std::max(at(p, kCells), edge(*south, p, 0));
  }
  rtin.propagate_errors(errors);
  const RtinMesh mesh = rtin.mesh(errors, max_error(level));

  const double spacing = 180.0 / static_cast<double>(rows);
  const geo::GeoBox rect = key.bounds();
  const LatticeGeometry geometry(rect.west - spacing, rect.north + spacing, spacing, kCorners + 2);
  QuantizedMeshInput in;
  in.rect = rect;
  in.triangles = mesh.triangles;
  const size_t n = mesh.vertex_count();
  in.u.resize(n), in.v.resize(n), in.height.resize(n);
  if (options.normals) in.normals.resize(n);
  for (size_t i = 0; i < n; ++i) {
    const int p = mesh.xy[2 * i], q = mesh.xy[2 * i + 1];
    in.u[i] = static_cast<uint16_t>((p * kQuantizedMax + kCells / 2) >> kLog2Cells);
    in.v[i] = static_cast<uint16_t>(((kCells - q) * kQuantizedMax + kCells / 2) >> kLog2Cells);
    in.height[i] = wide.at(p + 1, q + 1);
    if (!options.normals) continue;
    // Central differences of the full lattice (not of the simplified mesh),
    // in ECEF; neighbours' points come from the same global lattice, so a
    // shared edge vertex gets the same normal in both tiles. At a pole the
    // east-west difference vanishes: the ellipsoid's normal there.
    const int64_t global_row = row0 + q;
    if (global_row == 0 || global_row == rows) {
      in.normals[i] = geometry.up(p + 1, q + 1);
      continue;
    }
    const auto point = [&](int dp, int dq) {
      return geometry.at(p + 1 + dp, q + 1 + dq, wide.at(p + 1 + dp, q + 1 + dq));
    };
    const geo::Ecef east = minus(point(1, 0), point(-1, 0));
    const geo::Ecef north = minus(point(0, -1), point(0, 1));
    geo::Ecef normal{east.y * north.z - east.z * north.y, east.z * north.x - east.x * north.z,
                     east.x * north.y - east.y * north.x};
    const double length =
        std::sqrt(normal.x * normal.x + normal.y * normal.y + normal.z * normal.z);
    in.normals[i] = {normal.x / length, normal.y / length, normal.z / length};
  }
  // Tiles of every tenth level say what is available in the ten levels
  // below them (CesiumJS's metadataAvailability).
  if (key.level % kMetadataLevels == 0 && key.level < max_level) {
    in.metadata_json = metadata_json(*store, key, max_level, options.bbox);
  }
  return gzip(encode_quantized_mesh(in));
}

TerrainTiler::TerrainTiler(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
TerrainTiler::~TerrainTiler() = default;
TerrainTiler::TerrainTiler(TerrainTiler&&) noexcept = default;
TerrainTiler& TerrainTiler::operator=(TerrainTiler&&) noexcept = default;

Result<TerrainTiler> TerrainTiler::create(std::shared_ptr<const tiles::Store> store,
                                          TerrainOptions options) {
  const tiles::Manifest& m = store->manifest();
  if (m.kind != tiles::DatasetKind::Elevation || m.sample_type != tiles::SampleType::Float32 ||
      m.bands != 1) {
    return fail(fmt::format("{}: holds {}, not elevation: terrain tiles need an elevation store",
                            store->root().string(), tiles::to_string(m.kind)));
  }
  if (m.tile_log2_height != kLog2Cells) {
    return fail(fmt::format("{}: tiles of 2^{} rows; web tiles need the default 256",
                            store->root().string(), m.tile_log2_height));
  }
  auto impl = std::make_unique<Impl>(std::move(store), std::move(options));
  const int finest = impl->store->manifest().max_level;
  impl->max_level =
      impl->options.max_level < 0 ? finest : std::min(impl->options.max_level, finest);
  return TerrainTiler(std::move(impl));
}

int TerrainTiler::max_level() const {
  return impl_->max_level;
}
float TerrainTiler::max_error(int level) const {
  return impl_->max_error(level);
}

bool TerrainTiler::available(const TerrainKey& key) const {
  if (key.level < 0 || key.level > impl_->max_level) return false;
  if (key.x >= (2u << key.level) || key.y >= (1u << key.level)) return false;
  if (key.level == 0) return true;
  return impl_->meets_bbox(key) && impl_->store->has_tile(impl_->quad_of(key));
}

std::vector<TerrainKey> TerrainTiler::available_tiles(int level) const {
  return web::available_tiles(*impl_->store, level, impl_->max_level, impl_->options.bbox);
}

std::string TerrainTiler::layer_json(const std::string& name) const {
  return web::layer_json(*impl_->store, name, impl_->max_level, impl_->options.bbox,
                         impl_->options.normals);
}

Result<std::vector<std::byte>> TerrainTiler::tile(const TerrainKey& key) const {
  if (!available(key)) return fail(fmt::format("terrain tile {}: not available", key.to_string()));
  return impl_->tile(key);
}

}  // namespace relief::web
