#include "relief/ingest/build.h"

#include <fcntl.h>
#include <gdal.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <mutex>
#include <optional>
#include <set>
#include <unordered_map>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "core_store.h"
#include "gdal_env.h"
#include "memory_governor.h"
#include "output_guard.h"
#include "pyramid.h"
#include "relief/base/file_io.h"
#include "relief/base/first_error.h"
#include "relief/base/memory_use.h"
#include "relief/base/units.h"
#include "relief/tiles/geometric_error.h"
#include "relief/tiles/store.h"
#include "relief/tiles/store_layout.h"
#include "relief/tiles/store_source.h"
#include "source.h"
#include "task_graph.h"
#include "void_fill.h"
#include "warp.h"
#include "writeback.h"

namespace relief::ingest {
namespace fs = std::filesystem;
using geo::TileKey;

namespace {

constexpr int kMaxSupportedLevel = 24;

// --fill-voids: sources with voids are read from filled copies in the build
// directory (recomputed on resume: cheap next to warping). The other sources
// of a mosaic group that holds a filled one are copied too: the group must stay
// one mosaic of files of one format, or GDAL would leave the unfilled ones out
// (and splitting the group would change the samples along its seams).
Result<uint64_t> fill_voids_of_sources(const BuildOptions& o, std::vector<Source>& sources,
                                       const std::vector<MosaicGroup>& groups, Executor& executor) {
  auto copy_path = [&](size_t i) {
    return o.output / kBuildDir / "filled" / fmt::format("{}.tif", i);
  };
  std::vector<std::optional<Result<std::optional<FilledSource>>>> done(sources.size());
  executor.parallel_for(sources.size(), [&](size_t i) {
    done[i] = fill_source_voids(sources[i].read_path(), copy_path(i));
  });
  uint64_t filled = 0;
  for (size_t i = 0; i < sources.size(); ++i) {
    const std::optional<FilledSource> f = RELIEF_TRY(std::move(*done[i]));
    if (!f) continue;
    sources[i].filled = f->path.string();
    filled += f->filled;
  }
  std::vector<size_t> plain;  // unfilled members of groups with a filled member
  for (const MosaicGroup& g : groups) {
    const bool any = std::any_of(g.members.begin(), g.members.end(),
                                 [&](size_t m) { return !sources[m].filled.empty(); });
    for (size_t m : g.members) {
      if (any && sources[m].filled.empty()) plain.push_back(m);
    }
  }
  std::vector<std::optional<Result<std::optional<FilledSource>>>> copied(plain.size());
  executor.parallel_for(plain.size(), [&](size_t k) {
    copied[k] = fill_source_voids(sources[plain[k]].read_path(), copy_path(plain[k]), true);
  });
  for (size_t k = 0; k < plain.size(); ++k) {
    const std::optional<FilledSource> f = RELIEF_TRY(std::move(*copied[k]));
    sources[plain[k]].filled = f.value().path.string();
  }
  return filled;
}

// Infinite samples are nodata: no statistic, LOD error or colour ramp can use
// them. A store sample whose bilinear support touches one (inf, or inf - inf =
// NaN) is nodata too.
void drop_non_finite(tiles::Raster& core) {
  if (core.type() != tiles::SampleType::Float32) return;
  for (float& v : core.f32()) {
    if (!std::isfinite(v)) v = std::numeric_limits<float>::quiet_NaN();
  }
}

// Everything that determines the output. A resumed build must match it exactly.
std::string fingerprint(const BuildOptions& o, const tiles::CodecOptions& codec, int min_level,
                        int max_level) {
  nlohmann::json j;
  nlohmann::json inputs = nlohmann::json::array();
  for (const auto& in : o.inputs) {
    std::error_code ec;
    const auto size = fs::file_size(in, ec);
    const auto mtime = fs::last_write_time(in, ec).time_since_epoch().count();
    inputs.push_back(
        {{"path", fs::absolute(in).string()}, {"size", ec ? 0 : size}, {"mtime", mtime}});
  }
  j["inputs"] = inputs;
  j["kind"] = tiles::to_string(o.kind);
  j["levels"] = {min_level, max_level};
  j["codec"] = {tiles::to_string(codec.codec), codec.max_error, codec.quality};
  j["tile"] = {o.tile_log2_height, o.border};
  j["fill_voids"] = o.fill_voids;
  j["src_crs"] = o.src_crs.value_or("");
  j["warp_error"] = o.warp_error;
  j["direct"] = o.direct_resampling;
  return j.dump();
}

Status sync_filesystem(const fs::path& dir) {
  const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return fail(fmt::format("{}: cannot open: {}", dir.string(), errno_text(errno)));
  const int rc = ::syncfs(fd);
  const int err = errno;
  ::close(fd);
  if (rc != 0) return fail(fmt::format("{}: sync failed: {}", dir.string(), errno_text(err)));
  return {};
}

// A killed writer leaves its temporary file behind (never under a final name).
Status remove_temporary_files(const fs::path& root) {
  std::error_code ec;
  std::vector<fs::path> stale;
  for (auto it = fs::recursive_directory_iterator(root, ec);
       !ec && it != fs::recursive_directory_iterator(); it.increment(ec)) {
    if (it->is_regular_file() && is_temporary_file(it->path())) stale.push_back(it->path());
  }
  for (const auto& p : stale) {
    if (!fs::remove(p, ec) && ec)
      return fail(fmt::format("{}: cannot remove: {}", p.string(), ec.message()));
  }
  return {};
}

// Empties the build directory but for its state file, which marks the
// directory as an interrupted build of these parameters.
Status remove_scratch(const fs::path& out) {
  std::error_code ec;
  std::vector<fs::path> scratch;
  for (const auto& entry : fs::directory_iterator(out / kBuildDir, ec)) {
    if (entry.path().filename() != kStateName) scratch.push_back(entry.path());
  }
  for (const auto& p : scratch) {
    fs::remove_all(p, ec);
    if (ec) return fail(fmt::format("{}: cannot remove: {}", p.string(), ec.message()));
  }
  return {};
}

bool is_store_like(const fs::path& dir) {
  std::error_code ec;
  return fs::exists(dir / tiles::kManifestName, ec) || fs::exists(dir / kBuildDir / kStateName, ec);
}

// What to do with the output directory.
enum class OutputState {
  Fresh,     // nothing there (or replaced with --overwrite): build from scratch
  Resume,    // an interrupted build with the same parameters
  Finished,  // complete, but the build was stopped before removing .build/
};

// Decides whether to start fresh, resume, finish, or refuse.
Result<OutputState> prepare_output(const BuildOptions& o, const std::string& print) {
  std::error_code ec;
  const fs::path& out = o.output;
  RELIEF_CHECK(check_output_apart_from_inputs(out, o.inputs));
  if (fs::exists(out, ec) && !fs::is_directory(out, ec)) {
    return fail(fmt::format("{}: exists and is not a directory", out.string()));
  }
  const bool exists = fs::is_directory(out, ec);
  const bool empty = exists && fs::is_empty(out, ec);
  if (exists && !empty && !is_store_like(out)) {
    return fail(
        fmt::format("{}: exists and is not a relief store; choose another output", out.string()));
  }
  if (exists && is_store_like(out)) {
    const fs::path state = out / kBuildDir / kStateName;
    const bool complete = fs::exists(out / tiles::kManifestName, ec);
    const auto text = read_text_file(state, kMaxStateBytes);
    const bool same = text && *text == print;
    if (!o.overwrite) {
      // The manifest is written last, after every tile and index is durable:
      // a store with one is complete even if .build/ is still there.
      if (complete && fs::exists(out / kBuildDir, ec)) {
        if (same) return OutputState::Finished;
        return fail(
            fmt::format("{}: store already exists, with the scratch of an interrupted build "
                        "(run the same command again to finish it, or pass --overwrite)",
                        out.string()));
      }
      if (complete) {
        return fail(
            fmt::format("{}: store already exists (pass --overwrite to rebuild it)", out.string()));
      }
      if (same) return OutputState::Resume;
      return fail(
          fmt::format("{}: holds an interrupted build with other parameters "
                      "(pass --overwrite to start again)",
                      out.string()));
    }
    RELIEF_CHECK(check_only_store_files(out));
    fs::remove_all(out, ec);
    if (ec)
      return fail(fmt::format("{}: cannot remove the old store: {}", out.string(), ec.message()));
  }
  fs::create_directories(out / kBuildDir, ec);
  if (ec) return fail(fmt::format("{}: cannot create: {}", out.string(), ec.message()));
  RELIEF_CHECK(write_text_file_atomic(out / kBuildDir / kStateName, print));
  return OutputState::Fresh;
}

// Finishes a build stopped between its manifest and the removal of .build/.
Result<BuildReport> finish_cleanup(const fs::path& out) {
  const tiles::Store store = RELIEF_TRY(tiles::Store::open(out));
  RELIEF_CHECK(remove_temporary_files(out));
  std::error_code ec;
  fs::remove_all(out / kBuildDir, ec);
  if (ec)
    return fail(fmt::format("{}: cannot remove: {}", (out / kBuildDir).string(), ec.message()));
  BuildReport report;
  report.manifest = store.manifest();
  for (int l = report.manifest.min_level; l <= report.manifest.max_level; ++l) {
    report.tiles_resumed += store.index(l).size();
  }
  return report;
}

tiles::CodecOptions choose_codec(const BuildOptions& o) {
  tiles::CodecOptions c;
  c.max_error = o.max_error;
  c.quality = o.quality;
  if (o.codec)
    c.codec = *o.codec;
  else if (o.kind == tiles::DatasetKind::Imagery)
    c.codec = tiles::Codec::Jpeg;
  else if (o.max_error > 0)
    c.codec = tiles::Codec::Lerc;
  else
    c.codec = tiles::Codec::Zstd;
  return c;
}

Status validate_options(const BuildOptions& o, const tiles::CodecOptions& codec) {
  if (o.inputs.empty()) return fail("no input files given");
  if (o.output.empty()) return fail("-o: no output store given");
  if (o.fill_voids && o.kind != tiles::DatasetKind::Elevation) {
    return fail("--fill-voids: only for elevation (--kind elevation)");
  }
  const tiles::SampleType type =
      o.kind == tiles::DatasetKind::Imagery ? tiles::SampleType::UInt8 : tiles::SampleType::Float32;
  if (!tiles::codec_supports(codec.codec, type)) {
    return fail(fmt::format("--codec: {} cannot store {} data", tiles::to_string(codec.codec),
                            tiles::to_string(o.kind)));
  }
  if (o.max_error < 0 || !std::isfinite(o.max_error)) {
    return fail(fmt::format("--max-error: {} must be a non-negative number", o.max_error));
  }
  if (o.max_error > 0 && codec.codec != tiles::Codec::Lerc) {
    return fail("--max-error: only the lerc codec is lossy with a bounded error");
  }
  if (o.quality < 1 || o.quality > 100)
    return fail(fmt::format("--quality: {} is not in 1..100", o.quality));
  if (!(o.warp_error >= 0 && o.warp_error <= 10)) {
    return fail(fmt::format("--warp-error: {} is not in 0..10 pixels", o.warp_error));
  }
  return {};
}

// How --memory is spent. The budget covers the whole process: its code and
// libraries, each worker's buffers (warp destination, zstd contexts, a tile
// being assembled and encoded), and two caches that get what is left.
struct MemoryPlan {
  uint64_t gdal_cache = 0;  // GDAL's block cache for source reads
  uint64_t core_cache = 0;  // decoded tile interiors
};
constexpr uint64_t kMiB = uint64_t{1} << 20;
// Measured with `/usr/bin/time` and massif on two SRTM tiles: the libraries'
// pages are 43 MiB resident during a build, the allocator starts with 5 to
// 10 MiB of its own and strands some more between its arenas.
constexpr uint64_t kProcessReserve = 72 * kMiB;
constexpr uint64_t kWorkerReserve = 12 * kMiB;
constexpr uint64_t kMinimumCaches = 16 * kMiB;

Result<MemoryPlan> plan_memory(uint64_t budget, unsigned workers) {
  const uint64_t reserved = kProcessReserve + workers * kWorkerReserve;
  if (budget < reserved + kMinimumCaches) {
    return fail(
        fmt::format("--memory: {} MiB is too small for {} worker thread(s) (at least {} MiB)",
                    budget / kMiB, workers, (reserved + kMinimumCaches + kMiB - 1) / kMiB));
  }
  const uint64_t caches = budget - reserved;
  return MemoryPlan{caches / 3, caches - caches / 3};
}

// What GDAL's block cache must hold so that tiles, warped row by row, find
// the source blocks the row before them read: every source's rows under two
// rows of finest tiles, and a block above and below. Beyond that a block is
// not read again, and a larger cache only keeps memory that no one reuses
// (each block a fresh page: the Himalaya block's 24 .hgt files took 69 MiB
// of them and 16 000 page faults, for nothing).
uint64_t source_band_bytes(const std::vector<Source>& sources, int level) {
  const double band_degrees = 2 * 180.0 / TileKey::tiles_per_side(level);
  uint64_t bytes = 0;  // every source, though a band meets only some of them
  for (const Source& s : sources) {
    const double rows = std::min(static_cast<double>(s.height),
                                 band_degrees / s.spacing_deg + 2.0 * s.block_height + 2);
    const int bands = s.colour_bands + (s.has_alpha ? 1 : 0);
    bytes += static_cast<uint64_t>(static_cast<double>(s.width) * rows) *
             static_cast<uint64_t>(std::max(1, s.sample_bytes)) *
             static_cast<uint64_t>(std::max(1, bands));
  }
  return bytes;
}

// GDAL's cache at what the sources need (at least 16 MiB, at most its third
// of the caches); the interiors get the rest.
MemoryPlan fit_gdal_cache(MemoryPlan plan, uint64_t needed) {
  const uint64_t caches = plan.gdal_cache + plan.core_cache;
  const uint64_t gdal = std::min(std::max(needed, 16 * kMiB), plan.gdal_cache);
  return {gdal, caches - gdal};
}

// The tiles of `level` whose area meets `box` (columns may run past the
// antimeridian; the caller wraps them).
struct TileRange {
  int64_t x0, x1, y0, y1;
  uint64_t count() const { return static_cast<uint64_t>((x1 - x0 + 1) * (y1 - y0 + 1)); }
};
TileRange tiles_covering(const geo::GeoBox& box, int level) {
  const double n = TileKey::tiles_per_side(level);
  const auto col = [&](double lon) {
    return static_cast<int64_t>(std::floor((lon + 180.0) / 360.0 * n));
  };
  const auto row = [&](double lat) {
    return std::clamp<int64_t>(static_cast<int64_t>(std::floor((90.0 - lat) / 180.0 * n)), 0,
                               static_cast<int64_t>(n) - 1);
  };
  return {col(box.west), col(box.east), row(box.north), row(box.south)};
}

// What the build's plan (its task graph, the keys of every level, the
// indices) takes per finest tile, measured on a level-15 build of one SRTM
// tile; the coarser levels add a third.
constexpr uint64_t kPlanBytesPerTile = 1024;

// A build whose plan alone would not fit in a quarter of the memory budget is
// refused before anything is written: a sparse 1e6 x 1e6 input or a
// --max-level far past the data's own would otherwise grow without bound
// before its first tile.
Status check_plan_fits(const std::vector<Source>& sources, int max_level, uint64_t budget) {
  uint64_t tiles = 0;
  for (const Source& s : sources) tiles += tiles_covering(s.box, max_level).count();
  const uint64_t plan = (tiles + tiles / 3) * kPlanBytesPerTile;
  if (plan <= budget / 4) return {};
  return fail(fmt::format(
      "level {}: the inputs cover {} tiles, whose plan alone takes about {} of the --memory budget "
      "{}; give a lower --max-level, more --memory, or split the inputs",
      max_level, tiles, format_bytes(plan), format_bytes(budget)));
}

struct LevelResult {
  tiles::LevelIndex index;
  // Interior statistics of every tile, from the headers just written or found.
  std::vector<std::pair<TileKey, tiles::SampleStats>> tile_stats;
  uint64_t written = 0, resumed = 0;
};

struct WrittenTile {
  tiles::IndexEntry entry;
  tiles::SampleStats stats;
  bool resumed;
};

class Builder {
 public:
  Builder(const BuildOptions& o, std::vector<Source> sources, std::vector<MosaicGroup> groups,
          geo::TileGrid grid, tiles::CodecOptions codec, int min_level, int max_level,
          MemoryPlan memory, Executor& ex, Progress& progress)
      : o_(o),
        sources_(std::move(sources)),
        grid_(grid),
        codec_(codec),
        min_level_(min_level),
        max_level_(max_level),
        ex_(ex),
        progress_(progress),
        type_(o.kind == tiles::DatasetKind::Imagery ? tiles::SampleType::UInt8
                                                    : tiles::SampleType::Float32),
        groups_(std::move(groups)),
        cores_(o.output / kBuildDir / "cores",
               {type_, type_ == tiles::SampleType::UInt8 ? 4 : 1, grid.width(), grid.height(), 0},
               memory.core_cache),
        governor_(o.memory_budget,
                  {resident_set_bytes, o.release_freed_memory,
                   [this](uint64_t bytes) { return cores_.shrink_budget(bytes); }}) {}

  Result<BuildReport> run() {
    const auto start = std::chrono::steady_clock::now();
    BuildReport report;
    auto lap = [&, last = start](const char* phase) mutable {
      const auto now = std::chrono::steady_clock::now();
      report.phase_seconds.emplace_back(phase, std::chrono::duration<double>(now - last).count());
      last = now;
    };
    // Tiles start on their way to the disk as they are written (writeback.h).
    writeback_.emplace();
    std::vector<LevelResult> levels = RELIEF_TRY(build_levels());
    writeback_.reset();
    std::vector<tiles::LevelIndex> indices;
    tiles::SampleStats global;
    for (int level = min_level_; level <= max_level_; ++level) {
      LevelResult& r = levels[static_cast<size_t>(level - min_level_)];
      report.tiles_written += r.written;
      report.tiles_resumed += r.resumed;
      if (level == max_level_) global = combined_stats(std::move(r.tile_stats));
      indices.push_back(std::move(r.index));
    }
    lap("warp+pyramid+tiles");
    if (indices.back().size() == 0) {
      return fail(fmt::format("{}: the inputs hold no valid samples (nodata everywhere)",
                              o_.inputs.front()));
    }
    report.manifest = make_manifest(global);
    if (o_.kind == tiles::DatasetKind::Elevation) {
      // From the tile files just written: the errors of what readers decode.
      const tiles::TileShape shape = RELIEF_TRY(tiles::tile_shape_of(report.manifest));
      // The errors' cache of ancestors comes out of the cores' budget.
      RELIEF_CHECK(cores_.shrink_budget(
          tiles::ancestor_cache_bytes(shape, indices.size(), ex_.concurrency())));
      RELIEF_CHECK(tiles::compute_geometric_errors(indices, shape, tile_reader(shape), ex_,
                                                   progress_, interior_reader()));
      lap("errors");
    }
    for (const auto& index : indices) RELIEF_CHECK(tiles::write_level_index(o_.output, index));
    // Every tile is written: the scratch goes before the sync, so its dirty
    // pages (about as many bytes as the store) are dropped instead of written
    // to disk. A build stopped from here on resumes by computing the
    // interiors again and keeps the tiles already written.
    RELIEF_CHECK(remove_scratch(o_.output));
    // Tiles are renamed into place without fsync (atomic against a crash of the
    // process); one syncfs makes them all durable before the manifest declares
    // the store complete, so a power cut cannot leave a manifest over lost tiles.
    RELIEF_CHECK(sync_filesystem(o_.output));
    RELIEF_CHECK(tiles::write_manifest(o_.output, report.manifest));
    std::error_code ec;
    fs::remove_all(o_.output / kBuildDir, ec);  // scratch only; the store is complete
    lap("index+manifest");
    report.seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return report;
  }

 private:
  fs::path marker(const std::string& name) const {
    return o_.output / kBuildDir / (name + ".done");
  }
  bool done(const std::string& name) const {
    std::error_code ec;
    return fs::exists(marker(name), ec);
  }
  // A phase is marked done only when every core it made is on disk: the
  // cores held in memory die with a killed build, and a resumed one must
  // compute them again rather than skip the phase.
  Status mark_done(const std::string& name, int level) {
    if (!cores_.all_on_disk(level)) return {};
    return write_text_file_atomic(marker(name), "done\n");
  }

  std::vector<TileKey> finest_tiles() const {
    std::set<TileKey> keys;
    const auto n = static_cast<int64_t>(TileKey::tiles_per_side(max_level_));
    for (const auto& s : sources_) {
      const TileRange r = tiles_covering(s.box, max_level_);
      for (int64_t y = r.y0; y <= r.y1; ++y) {
        for (int64_t x = r.x0; x <= r.x1; ++x) {
          const int64_t wrapped = ((x % n) + n) % n;
          keys.insert({max_level_, static_cast<uint32_t>(wrapped), static_cast<uint32_t>(y)});
        }
      }
    }
    std::vector<TileKey> sorted(keys.begin(), keys.end());
    std::sort(sorted.begin(), sorted.end(),
              [](const auto& a, const auto& b) { return std::tie(a.y, a.x) < std::tie(b.y, b.x); });
    return sorted;
  }

  // The warp, the pyramid and the tiles as one graph of tasks (task_graph.h):
  // a parent core is made as soon as its four children exist and a tile is
  // written as soon as its 3 x 3 neighbourhood of cores exists, so both
  // workers stay busy across what used to be phase boundaries (while one
  // reads the sources, the other encodes tiles). Every task is a function of
  // the inputs alone, so the store does not depend on the order.
  Result<std::vector<LevelResult>> build_levels() {
    enum class Kind { Warp, Parent, Tile };
    struct Job {
      Kind kind;
      TileKey key;
    };
    // Warps first (they feed everything else), then parents (the pyramid's
    // top is a chain of single tasks), then tiles.
    constexpr int kWarpClass = 0, kParentClass = 1, kTileClass = 2;
    const auto levels = static_cast<size_t>(max_level_ - min_level_ + 1);
    auto slot = [&](int level) { return static_cast<size_t>(level - min_level_); };
    TaskGraph graph;
    std::vector<Job> jobs;
    // Per level: the cores' keys in task order, and their tasks.
    std::vector<std::vector<TileKey>> cores(levels);
    std::vector<std::unordered_map<TileKey, size_t, geo::TileKeyHash>> core_task(levels);
    auto add_core = [&](Kind kind, int task_class, const TileKey& key) {
      const size_t id = graph.add(task_class);
      jobs.push_back({kind, key});
      cores[slot(key.level)].push_back(key);
      core_task[slot(key.level)].emplace(key, id);
      return id;
    };
    for (const TileKey& key : finest_tiles()) add_core(Kind::Warp, kWarpClass, key);
    for (int level = max_level_ - 1; level >= min_level_; --level) {
      std::set<TileKey> parents;
      for (const TileKey& child : cores[slot(level + 1)]) parents.insert(*child.parent());
      for (const TileKey& p : parents) {
        const size_t id = add_core(Kind::Parent, kParentClass, p);
        for (int c = 0; c < 4; ++c) {
          const auto& below = core_task[slot(level + 1)];
          if (auto it = below.find(p.child(c % 2, c / 2)); it != below.end())
            graph.depend(id, it->second);
        }
      }
    }
    for (int level = max_level_; level >= min_level_; --level) {
      const auto& around = core_task[slot(level)];
      for (const TileKey& key : cores[slot(level)]) {
        const size_t id = graph.add(kTileClass);
        jobs.push_back({Kind::Tile, key});
        std::set<size_t> prerequisites;
        for (int dy = -1; dy <= 1; ++dy) {
          for (int dx = -1; dx <= 1; ++dx) {
            const auto n = key.neighbour(dx, dy);
            if (!n) continue;
            if (auto it = around.find(*n); it != around.end()) prerequisites.insert(it->second);
          }
        }
        for (size_t q : prerequisites) graph.depend(id, q);
      }
    }

    // A phase marker per level, once its last core is made (mark_done).
    std::vector<std::atomic<size_t>> unmade(levels);
    std::vector<bool> skipped(levels);
    for (int level = min_level_; level <= max_level_; ++level) {
      unmade[slot(level)] = cores[slot(level)].size();
      skipped[slot(level)] = done(phase_name(level));
    }
    std::vector<LevelResult> results;
    for (int level = min_level_; level <= max_level_; ++level)
      results.push_back({tiles::LevelIndex(level), {}, 0, 0});
    std::mutex results_mutex;
    Warpers warpers(groups_.size());
    FirstError error;
    progress_.begin(fmt::format("levels {}..{}", max_level_, min_level_), jobs.size());
    graph.run(ex_, [&](size_t id) {
      const Job& job = jobs[id];
      const size_t s = slot(job.key.level);
      if (!error.failed()) {
        Status status;
        if (job.kind == Kind::Tile) {
          // No core, no tile: the tile would be empty.
          if (cores_.exists(job.key)) {
            if (auto tile = write_tile(job.key); !tile) {
              status = std::unexpected(tile.error());
            } else {
              std::lock_guard lock(results_mutex);
              LevelResult& r = results[s];
              r.index.add(tile->entry);
              r.tile_stats.emplace_back(job.key, tile->stats);
              (tile->resumed ? r.resumed : r.written) += 1;
            }
          }
        } else {
          if (!skipped[s] && !cores_.exists(job.key)) {
            status = job.kind == Kind::Warp ? warp_core(job.key, warpers) : parent_core(job.key);
          }
          if (status && --unmade[s] == 0)
            status = mark_done(phase_name(job.key.level), job.key.level);
        }
        if (status) status = governor_.check();
        if (!status) error.set(status.error());
      }
      progress_.advance();
    });
    progress_.end();
    RELIEF_CHECK(error.status());
    return results;
  }

  std::string phase_name(int level) const {
    return fmt::format("{}-{}", level == max_level_ ? "warp" : "pyramid", level);
  }

  // One warper per concurrent worker, and the direct path's shared datasets.
  struct Warpers {
    explicit Warpers(size_t groups) : shared(groups) {}
    std::mutex mutex;
    std::vector<std::unique_ptr<TileWarper>> idle;
    SharedDirectSources shared;  // read once for all workers
  };

  Status warp_core(const TileKey& key, Warpers& warpers) {
    std::unique_ptr<TileWarper> warper;
    {
      std::lock_guard lock(warpers.mutex);
      if (!warpers.idle.empty()) {
        warper = std::move(warpers.idle.back());
        warpers.idle.pop_back();
      }
    }
    if (!warper) {
      warper = std::make_unique<TileWarper>(sources_, groups_, o_.kind, grid_, o_.warp_error,
                                            o_.direct_resampling, &warpers.shared);
    }
    auto core = warper->warp(key);
    {
      std::lock_guard lock(warpers.mutex);
      warpers.idle.push_back(std::move(warper));
    }
    if (!core) return std::unexpected(core.error());
    drop_non_finite(*core);
    if (!core->any_valid()) return {};
    return cores_.write(key, std::move(*core));
  }

  // A parent core from its children; none when all four are empty.
  Status parent_core(const TileKey& p) {
    std::array<std::shared_ptr<const tiles::Raster>, 4> held;
    std::array<const tiles::Raster*, 4> children{};
    for (size_t c = 0; c < 4; ++c) {
      held[c] = RELIEF_TRY(cores_.read(p.child(static_cast<int>(c % 2), static_cast<int>(c / 2))));
      children[c] = held[c].get();
    }
    if (std::all_of(children.begin(), children.end(), [](auto* c) { return c == nullptr; }))
      return {};
    return cores_.write(p, downsample(children, grid_.width(), grid_.height(), type_));
  }

  // A tile as written, before encoding: its core with borders from its neighbours'.
  Result<tiles::Raster> bordered_tile(const TileKey& key) {
    std::array<std::shared_ptr<const tiles::Raster>, 9> held;
    std::array<const tiles::Raster*, 9> around{};
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) {
        auto n = key.neighbour(dx, dy);
        if (!n) continue;
        auto core = RELIEF_TRY(cores_.read(*n));
        const size_t slot = static_cast<size_t>((dy + 1) * 3 + dx + 1);
        held[slot] = core;
        around[slot] = core.get();
      }
    }
    return assemble_bordered(around, grid_.width(), grid_.height(), grid_.border(), type_);
  }

  // The written tiles for the geometric errors. A lossless codec gives back
  // exactly what it encoded: the tiles are assembled again from the cores
  // (mostly still cached) instead of read and decoded; a lossy one's errors
  // are those of the decoded tiles, which readers see.
  tiles::BorderedTileReader tile_reader(const tiles::TileShape& shape) {
    if (codec_.codec != tiles::Codec::Zstd) return tiles::directory_tile_reader(o_.output, shape);
    return [this](const TileKey& key) -> Result<std::shared_ptr<const tiles::Raster>> {
      RELIEF_CHECK(governor_.check());
      return std::make_shared<const tiles::Raster>(RELIEF_TRY(bordered_tile(key)));
    };
  }

  // The finest tiles' interiors for the geometric errors: their cores, not
  // copied into a bordered tile. Lossless codecs only (see tile_reader).
  tiles::BorderedTileReader interior_reader() {
    if (codec_.codec != tiles::Codec::Zstd) return {};
    return [this](const TileKey& key) -> Result<std::shared_ptr<const tiles::Raster>> {
      RELIEF_CHECK(governor_.check());
      return cores_.read(key);
    };
  }

  // Writes one bordered tile unless a valid one is already there.
  Result<WrittenTile> write_tile(const TileKey& key) {
    const fs::path path = o_.output / tiles::tile_relative_path(key);
    std::error_code ec;
    if (fs::exists(path, ec)) {
      // Any size a tile may have: a larger one is rewritten below.
      auto bytes =
          read_file(path, tiles::max_file_bytes(tiles::tile_relative_path(key), std::nullopt));
      if (bytes) {
        if (auto h = tiles::parse_tile_header(*bytes, path.string())) {
          return WrittenTile{tiles::index_entry_for(key, *h, bytes->size()), h->stats, true};
        }
      }
    }
    const tiles::Raster bordered = RELIEF_TRY(bordered_tile(key));
    auto bytes = RELIEF_TRY(tiles::encode_tile(bordered, grid_.border(), codec_));
    RELIEF_CHECK(tiles::write_tile_file(o_.output, key, bytes));
    if (writeback_) writeback_->start(path);
    auto header = RELIEF_TRY(tiles::parse_tile_header(bytes, path.string()));
    return WrittenTile{tiles::index_entry_for(key, header, bytes.size()), header.stats, false};
  }

  tiles::Manifest make_manifest(const tiles::SampleStats& stats) {
    tiles::Manifest m;
    m.kind = o_.kind;
    m.sample_type = type_;
    m.bands = type_ == tiles::SampleType::Float32 ? 1 : 4;
    m.units = o_.kind == tiles::DatasetKind::Elevation ? "m"
              : o_.kind == tiles::DatasetKind::Sar     ? "amplitude"
                                                       : "";
    m.tile_log2_height = grid_.log2_height();
    m.border = grid_.border();
    m.min_level = min_level_;
    m.max_level = max_level_;
    m.codec = codec_;
    m.created_by = "relief build";
    m.extent = sources_.front().box;
    for (const auto& s : sources_) {
      m.extent.west = std::min(m.extent.west, s.box.west);
      m.extent.south = std::min(m.extent.south, s.box.south);
      m.extent.east = std::max(m.extent.east, s.box.east);
      m.extent.north = std::max(m.extent.north, s.box.north);
      m.sources.push_back(to_source_info(s));
    }
    m.stats = stats;
    return m;
  }

  // Global statistics from the finest tiles' interior statistics (borders are
  // left out, so no sample counts twice), combined in tile order so the
  // manifest does not depend on which thread finished first.
  tiles::SampleStats combined_stats(std::vector<std::pair<TileKey, tiles::SampleStats>> tiles) {
    std::sort(tiles.begin(), tiles.end(), [](const auto& a, const auto& b) {
      return std::tie(a.first.y, a.first.x) < std::tie(b.first.y, b.first.x);
    });
    std::vector<tiles::SampleStats> parts;
    for (const auto& t : tiles) parts.push_back(t.second);
    return tiles::combine_stats(parts, type_ == tiles::SampleType::UInt8 ? 3 : 1);
  }

  const BuildOptions& o_;
  std::vector<Source> sources_;
  geo::TileGrid grid_;
  tiles::CodecOptions codec_;
  int min_level_, max_level_;
  Executor& ex_;
  Progress& progress_;
  tiles::SampleType type_;
  std::vector<MosaicGroup> groups_;
  CoreStore cores_;
  MemoryGovernor governor_;
  std::optional<Writeback> writeback_;  // while tiles are written
};

}  // namespace

Result<BuildReport> build_store(const BuildOptions& o, Executor& executor, Progress& progress) {
  const tiles::CodecOptions codec = choose_codec(o);
  RELIEF_CHECK(validate_options(o, codec));
  auto grid = geo::TileGrid::create(o.tile_log2_height, o.border);
  if (!grid) return fail(fmt::format("--tile-size/--border: {}", grid.error().message));

  MemoryPlan memory = RELIEF_TRY(plan_memory(o.memory_budget, executor.concurrency()));
  init_gdal();
  // Opening thousands of inputs (a continent of SRTM tiles) is worth doing in
  // parallel; the first bad input in command-line order is the one reported.
  std::vector<std::optional<Result<Source>>> described(o.inputs.size());
  executor.parallel_for(o.inputs.size(), [&](size_t i) {
    described[i] = describe_source(o.inputs[i], o.kind, o.src_crs);
  });
  std::vector<Source> sources;
  for (auto& d : described) sources.push_back(RELIEF_TRY(std::move(*d)));
  RELIEF_CHECK(check_compatible(sources));

  double finest_spacing = std::numeric_limits<double>::infinity();
  for (const auto& s : sources) finest_spacing = std::min(finest_spacing, s.spacing_deg);
  const int max_level = o.max_level.value_or(grid->level_for_spacing(finest_spacing));
  const int min_level = o.min_level.value_or(0);
  if (max_level < 0 || max_level > kMaxSupportedLevel) {
    return fail(fmt::format("--max-level: {} is not in 0..{}", max_level, kMaxSupportedLevel));
  }
  if (min_level < 0 || min_level > max_level) {
    return fail(fmt::format("--min-level: {} is not in 0..{}", min_level, max_level));
  }
  RELIEF_CHECK(check_plan_fits(sources, max_level, o.memory_budget));
  memory = fit_gdal_cache(memory, source_band_bytes(sources, max_level));
  GDALSetCacheMax64(static_cast<GIntBig>(memory.gdal_cache));
  const std::string print = fingerprint(o, codec, min_level, max_level);
  const OutputState state = RELIEF_TRY(prepare_output(o, print));
  if (state == OutputState::Finished) return finish_cleanup(o.output);
  if (state == OutputState::Resume) RELIEF_CHECK(remove_temporary_files(o.output));
  const auto start = std::chrono::steady_clock::now();
  // Grouped before void filling, which must not change how sources mosaic.
  std::vector<MosaicGroup> groups = group_sources(sources);
  const uint64_t filled =
      o.fill_voids ? RELIEF_TRY(fill_voids_of_sources(o, sources, groups, executor)) : 0;
  const double fill_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  Builder builder(o, std::move(sources), std::move(groups), *grid, codec, min_level, max_level,
                  memory, executor, progress);
  BuildReport report = RELIEF_TRY(builder.run());
  report.voids_filled = filled;
  if (o.fill_voids) {
    report.phase_seconds.insert(report.phase_seconds.begin(), {"voids", fill_seconds});
    report.seconds += fill_seconds;
  }
  return report;
}

}  // namespace relief::ingest
