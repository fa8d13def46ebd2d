#include "store_output.h"

#include <unistd.h>

#include <algorithm>

#include <fmt/format.h>

#include "relief/base/file_io.h"
#include "relief/tiles/assemble.h"
#include "relief/tiles/geometric_error.h"

namespace relief::pipeline {

namespace fs = std::filesystem;

Result<StoreOutput> StoreOutput::create(const fs::path& output, int min_level, int max_level) {
  std::error_code ec;
  if (fs::exists(output, ec)) {
    return fail(fmt::format("{}: already exists; choose a new output directory", output.string()));
  }
  const fs::path parent = output.has_parent_path() ? output.parent_path() : fs::path(".");
  if (!fs::is_directory(parent, ec)) {
    return fail(fmt::format("{}: no such directory", parent.string()));
  }
  // A killed fuse or process left its temporary directory: remove those of
  // dead processes (never another running one's).
  static_cast<void>(remove_stale_temporaries_of(output));
  fs::path temp = output;
  temp += fmt::format("{}{}", kTempMarker, ::getpid());
  fs::remove_all(temp, ec);
  if (!fs::create_directory(temp, ec)) {
    return fail(fmt::format("{}: cannot create: {}", temp.string(), ec.message()));
  }
  return StoreOutput(output, temp, min_level, max_level);
}

StoreOutput::StoreOutput(fs::path output, fs::path temp, int min_level, int max_level)
    : output_(std::move(output)), temp_(std::move(temp)), min_level_(min_level) {
  for (int l = min_level; l <= max_level; ++l) indices_.emplace_back(l);
}

StoreOutput::~StoreOutput() {
  if (!finished_ && !temp_.empty()) {
    std::error_code ec;
    fs::remove_all(temp_, ec);
  }
}

Status StoreOutput::write(const geo::TileKey& key, const tiles::Raster& bordered, int border,
                          const tiles::CodecOptions& codec, const tiles::IndexEntry* bounds) {
  auto bytes = RELIEF_TRY(tiles::encode_tile(bordered, border, codec));
  RELIEF_CHECK(tiles::write_tile_file(temp_, key, bytes));
  auto header = RELIEF_TRY(tiles::parse_tile_header(bytes, key.to_string()));
  tiles::IndexEntry entry = tiles::index_entry_for(key, header, bytes.size());
  if (bounds) {
    entry.min = bounds->min;
    entry.max = bounds->max;
  }
  std::lock_guard lock(*mutex_);
  indices_[static_cast<size_t>(key.level - min_level_)].add(entry);
  if (key.level == indices_.back().level()) finest_stats_.emplace_back(key, header.stats);
  ++written_;
  return {};
}

Status StoreOutput::finish(tiles::Manifest manifest, Executor& executor, Progress& progress) {
  std::sort(finest_stats_.begin(), finest_stats_.end(), [](const auto& a, const auto& b) {
    return std::tie(a.first.y, a.first.x) < std::tie(b.first.y, b.first.x);
  });
  std::vector<tiles::SampleStats> parts;
  for (const auto& s : finest_stats_) parts.push_back(s.second);
  manifest.stats =
      tiles::combine_stats(parts, manifest.sample_type == tiles::SampleType::UInt8 ? 3 : 1);
  if (manifest.kind == tiles::DatasetKind::Elevation) {
    const tiles::TileShape shape = RELIEF_TRY(tiles::tile_shape_of(manifest));
    RELIEF_CHECK(tiles::compute_geometric_errors(
        indices_, shape, tiles::directory_tile_reader(temp_, shape), executor, progress));
  }
  for (const auto& index : indices_) RELIEF_CHECK(tiles::write_level_index(temp_, index));
  RELIEF_CHECK(tiles::write_manifest(temp_, manifest));
  std::error_code ec;
  fs::rename(temp_, output_, ec);
  if (ec)
    return fail(fmt::format("{}: cannot move into place: {}", output_.string(), ec.message()));
  finished_ = true;
  return {};
}

}  // namespace relief::pipeline
