#include "relief/net/disk_cache.h"

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <condition_variable>
#include <cstring>
#include <list>
#include <map>
#include <mutex>
#include <optional>
#include <span>
#include <string_view>

#include <fmt/format.h>

#include "relief/base/file_io.h"
#include "relief/tiles/store_layout.h"
#include "relief/tiles/store_source.h"

namespace relief::net {
namespace {

namespace fs = std::filesystem;

// FNV-1a: the same across runs and builds, as cache keys on disk must be
// (std::hash need not be).
uint64_t stable_hash(std::string_view bytes) {
  uint64_t h = 0xcbf29ce484222325ULL;
  for (char c : bytes) {
    h ^= static_cast<unsigned char>(c);
    h *= 0x100000001b3ULL;
  }
  return h;
}
// The names of the cache's location directories: 16 hex digits.
bool is_location_name(std::string_view name) {
  return name.size() == 16 && std::all_of(name.begin(), name.end(), [](char c) {
           return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f');
         });
}
std::string as_text(std::span<const std::byte> bytes) {
  return {reinterpret_cast<const char*>(bytes.data()), bytes.size()};
}

// The manifest most recently cached for a store location (under its
// directory, one subdirectory per manifest seen there), for offline runs.
std::optional<std::pair<fs::path, std::vector<std::byte>>> newest_cached_manifest(
    const fs::path& location_dir) {
  std::optional<std::pair<fs::path, std::vector<std::byte>>> newest;
  fs::file_time_type newest_time{};
  std::error_code ec;
  for (auto it = fs::directory_iterator(location_dir, ec); !ec && it != fs::directory_iterator();
       it.increment(ec)) {
    const fs::path file = it->path() / tiles::kManifestName;
    const auto time = fs::last_write_time(file, ec);
    if (ec || (newest && time <= newest_time)) {
      ec.clear();
      continue;
    }
    auto bytes = read_file(file, tiles::kMaxManifestBytes);
    if (!bytes || !tiles::StoreSource::verify(tiles::kManifestName, *bytes)) continue;
    newest.emplace(it->path(), std::move(*bytes));
    newest_time = time;
  }
  return newest;
}

class Cache final : public DiskCache {
 public:
  // Files of this store live under dir/store_rel; the manifest is the one
  // that named them.
  Cache(std::shared_ptr<const tiles::StoreSource> upstream, fs::path dir, uint64_t budget,
        fs::path store_rel, std::vector<std::byte> manifest)
      : upstream_(std::move(upstream)),
        dir_(std::move(dir)),
        budget_(budget),
        store_rel_(std::move(store_rel)),
        manifest_(std::move(manifest)) {}

  fs::path store_directory() const override { return dir_ / store_rel_; }

  // Keeps the manifest beside the store's files, for offline runs.
  void keep_manifest() {
    const std::string key = (store_rel_ / tiles::kManifestName).generic_string();
    if (manifest_.size() <= budget_ && write_file_atomic(dir_ / key, manifest_)) {
      std::lock_guard lock(mutex_);
      add_locked(key, manifest_.size());
    }
  }

  // Existing files, oldest first, become the initial LRU order. Only those
  // under the cache's own location directories count (and may be evicted):
  // a cache directory shared with anything else keeps the rest.
  void load_existing() {
    std::vector<std::pair<fs::file_time_type, fs::path>> files;
    std::error_code ec;
    for (auto top = fs::directory_iterator(dir_, ec); !ec && top != fs::directory_iterator();
         top.increment(ec)) {
      if (!is_location_name(top->path().filename().string()) || !top->is_directory(ec)) continue;
      std::error_code walk;
      for (auto it = fs::recursive_directory_iterator(top->path(), walk);
           !walk && it != fs::recursive_directory_iterator(); it.increment(walk)) {
        std::error_code entry;
        if (!it->is_regular_file(entry) ||
            it->path().filename().string().find(kTempMarker) != std::string::npos) {
          continue;
        }
        const auto time = it->last_write_time(entry);
        if (!entry) files.emplace_back(time, it->path());
      }
    }
    std::sort(files.begin(), files.end());
    for (const auto& [time, path] : files) {
      const std::string rel = path.lexically_relative(dir_).generic_string();
      const uint64_t size = fs::file_size(path, ec);
      if (ec) continue;
      order_.push_front(rel);
      entries_[rel] = {size, order_.begin()};
      bytes_ += size;
    }
    evict_locked();
  }

  std::string name() const override { return upstream_->name(); }

  DiskCacheStats stats() const override {
    std::lock_guard lock(mutex_);
    return {hits_, misses_, evictions_, shared_, repaired_, bytes_};
  }

  Result<std::vector<std::byte>> fetch(const std::string& rel) const override {
    // The manifest that keys the cache is the one the store reads.
    if (rel == tiles::kManifestName) return manifest_;
    const std::string key = (store_rel_ / rel).generic_string();
    std::unique_lock lock(mutex_);
    if (auto it = entries_.find(key); it != entries_.end()) {
      order_.splice(order_.begin(), order_, it->second.position);
      lock.unlock();
      auto bytes = read_file(dir_ / key, tiles::max_file_bytes(rel, std::nullopt));
      if (bytes && tiles::StoreSource::verify(rel, *bytes)) {
        std::lock_guard relock(mutex_);
        ++hits_;
        return bytes;
      }
      lock.lock();  // missing or damaged: forget it and fetch anew
      ++repaired_;
      drop_locked(key);
    }
    // One upstream fetch per file at a time; others wait for its result.
    if (auto it = in_flight_.find(key); it != in_flight_.end()) {
      auto flight = it->second;
      ++shared_;
      ready_.wait(lock, [&] { return flight->done; });
      if (flight->result) return flight->result;
      return std::unexpected(flight->result.error());
    }
    auto flight = std::make_shared<Flight>();
    in_flight_[key] = flight;
    ++misses_;
    lock.unlock();
    Result<std::vector<std::byte>> result = upstream_->fetch(rel);
    // A file larger than the whole budget is not kept (a budget of 0 keeps nothing).
    if (result && result->size() <= budget_ && write_file_atomic(dir_ / key, *result)) {
      std::lock_guard relock(mutex_);
      add_locked(key, result->size());
    }
    lock.lock();
    flight->result = result;
    flight->done = true;
    in_flight_.erase(key);
    ready_.notify_all();
    return result;
  }

 private:
  struct Entry {
    uint64_t size;
    std::list<std::string>::iterator position;
  };
  struct Flight {
    bool done = false;
    Result<std::vector<std::byte>> result = fail("pending");
  };

  void add_locked(const std::string& key, uint64_t size) const {
    if (auto it = entries_.find(key); it != entries_.end()) {  // rewritten in place
      bytes_ -= it->second.size;
      order_.erase(it->second.position);
    }
    order_.push_front(key);
    entries_[key] = {size, order_.begin()};
    bytes_ += size;
    evict_locked();
  }

  void drop_locked(std::string rel) const {  // by value: it may name an order_ element
    auto it = entries_.find(rel);
    if (it == entries_.end()) return;
    bytes_ -= it->second.size;
    order_.erase(it->second.position);
    entries_.erase(it);
    std::error_code ec;
    fs::remove(dir_ / rel, ec);
  }

  void evict_locked() const {
    while (bytes_ > budget_ && !order_.empty()) {
      drop_locked(order_.back());
      ++evictions_;
    }
  }

  std::shared_ptr<const tiles::StoreSource> upstream_;
  fs::path dir_;
  uint64_t budget_;
  fs::path store_rel_;
  std::vector<std::byte> manifest_;
  mutable std::mutex mutex_;
  mutable std::condition_variable ready_;
  mutable std::list<std::string> order_;  // most recently used first
  mutable std::map<std::string, Entry> entries_;
  mutable std::map<std::string, std::shared_ptr<Flight>> in_flight_;
  mutable uint64_t bytes_ = 0, hits_ = 0, misses_ = 0, evictions_ = 0, shared_ = 0, repaired_ = 0;
};

}  // namespace

Result<std::shared_ptr<DiskCache>> DiskCache::create(
    std::shared_ptr<const tiles::StoreSource> upstream, const fs::path& directory,
    uint64_t budget_bytes) {
  std::error_code ec;
  fs::create_directories(directory, ec);
  if (!fs::is_directory(directory, ec)) {
    return fail(fmt::format("{}: cannot create the cache directory{}", directory.string(),
                            ec ? ": " + ec.message() : std::string()));
  }
  // Keyed by the store's identity, its location and its manifest (fetched
  // anew every time): two stores, or a store rebuilt at the same URL, never
  // share files. When the upstream cannot be reached, the last manifest seen
  // at that location is used, so a second run works offline.
  const fs::path location_rel = fmt::format("{:016x}", stable_hash(upstream->name()));
  fs::path store_rel;
  std::vector<std::byte> manifest;
  if (auto fresh = upstream->fetch(tiles::kManifestName)) {
    manifest = std::move(*fresh);
    store_rel = location_rel / fmt::format("{:016x}", stable_hash(as_text(manifest)));
  } else if (auto cached = newest_cached_manifest(directory / location_rel)) {
    store_rel = location_rel / cached->first.filename();
    manifest = std::move(cached->second);
  } else {
    return std::unexpected(fresh.error());
  }
  // Where this store's files go must be a directory the cache can write in
  // (not /proc, a read-only mount or a file in the way).
  fs::create_directories(directory / store_rel, ec);
  if (ec || !fs::is_directory(directory / store_rel, ec) ||
      ::access((directory / store_rel).c_str(), W_OK | X_OK) != 0) {
    return fail(
        fmt::format("{}: not a directory the disk cache can write in (creating {} in it: {})",
                    directory.string(), store_rel.parent_path().string(),
                    ec ? ec.message() : std::string(std::strerror(errno))));
  }
  auto cache = std::make_shared<Cache>(std::move(upstream), directory, budget_bytes,
                                       std::move(store_rel), std::move(manifest));
  cache->load_existing();
  cache->keep_manifest();
  return std::shared_ptr<DiskCache>(std::move(cache));
}

}  // namespace relief::net
