#include "relief/tiles/split.h"

#include <optional>

#include <fmt/format.h>

#include "relief/base/file_io.h"
#include "relief/tiles/store.h"
#include "relief/tiles/store_layout.h"

namespace relief::tiles {

namespace fs = std::filesystem;

namespace {

// A hard link where the file system allows (store files are never modified
// in place, only replaced, so sharing them is safe), else a copy. Only a
// regular file (not a symlink, which the link would carry to /etc/passwd, nor
// a FIFO or device) of the size the store expects goes into a share, which a
// plain server then serves.
Result<bool> link_or_copy(const fs::path& from, const fs::path& to,
                          std::optional<uint64_t> expected_bytes) {
  std::error_code ec;
  const fs::file_status status = fs::symlink_status(from, ec);
  if (ec || !fs::is_regular_file(status)) {
    return fail(fmt::format("{}: is {}, not a regular file", from.string(),
                            fs::is_symlink(status) ? "a symbolic link" : "not a file to share"));
  }
  if (const uint64_t size = fs::file_size(from, ec);
      expected_bytes && (ec || size != *expected_bytes)) {
    return fail(fmt::format("{}: {} bytes, not the {} the store lists for it", from.string(), size,
                            *expected_bytes));
  }
  fs::create_directories(to.parent_path(), ec);
  if (ec) return fail(fmt::format("{}: {}", to.parent_path().string(), ec.message()));
  fs::create_hard_link(from, to, ec);
  if (!ec) return true;
  fs::copy_file(from, to, ec);
  if (ec) return fail(fmt::format("{}: {}", to.string(), ec.message()));
  return false;
}

}  // namespace

fs::path share_directory(const fs::path& output, uint32_t index) {
  return output / fmt::format("share-{}", index);
}

Result<SplitReport> split_store(const fs::path& root, const fs::path& output, uint32_t shares) {
  if (shares < 2 || shares > 4096) {
    return fail(fmt::format("--shares: {} is not in [2, 4096]", shares));
  }
  const Store store = RELIEF_TRY(Store::open(root));
  std::error_code ec;
  if (fs::exists(fs::symlink_status(output, ec))) {
    return fail(fmt::format("{}: already exists", output.string()));
  }
  RELIEF_TRY(remove_stale_temporaries_of(output));
  const fs::path temp = temporary_name(output);
  SplitReport report;
  auto write = [&]() -> Status {
    const Manifest& m = store.manifest();
    for (uint32_t i = 0; i < shares; ++i) {
      const fs::path dir = share_directory(temp, i);
      // The manifest and indices are the ones Store::open read and checked.
      RELIEF_TRY(link_or_copy(root / kManifestName, dir / kManifestName, std::nullopt));
      for (int level = m.min_level; level <= m.max_level; ++level) {
        const std::string index = level_index_relative_path(level);
        RELIEF_TRY(link_or_copy(root / index, dir / index, store.index(level).serialize().size()));
      }
    }
    for (int level = m.min_level; level <= m.max_level; ++level) {
      for (const IndexEntry& e : store.index(level).entries()) {
        const std::string tile = tile_relative_path(e.key);
        const auto share = static_cast<uint32_t>(e.key.morton() % shares);
        report.linked += RELIEF_TRY(
            link_or_copy(root / tile, share_directory(temp, share) / tile, e.file_bytes));
        ++report.tiles;
      }
    }
    fs::rename(temp, output, ec);
    if (ec) return fail(fmt::format("{}: {}", output.string(), ec.message()));
    return {};
  };
  if (auto done = write(); !done) {
    fs::remove_all(temp, ec);
    return std::unexpected(done.error());
  }
  return report;
}

}  // namespace relief::tiles
