#include "relief/net/disk_cache.h"

#include <algorithm>
#include <condition_variable>
#include <list>
#include <map>
#include <mutex>

#include <fmt/format.h>

#include "relief/base/file_io.h"

namespace relief::net {
namespace {

namespace fs = std::filesystem;

class Cache final : public DiskCache {
 public:
  Cache(std::shared_ptr<const tiles::StoreSource> upstream, fs::path dir, uint64_t budget)
      : upstream_(std::move(upstream)), dir_(std::move(dir)), budget_(budget) {}

  // Existing files, oldest first, become the initial LRU order.
  void load_existing() {
    std::vector<std::pair<fs::file_time_type, fs::path>> files;
    std::error_code ec;
    for (auto it = fs::recursive_directory_iterator(dir_, ec);
         it != fs::recursive_directory_iterator(); it.increment(ec)) {
      if (ec) break;
      if (!it->is_regular_file() ||
          it->path().filename().string().find(kTempMarker) != std::string::npos) {
        continue;
      }
      files.emplace_back(it->last_write_time(), it->path());
    }
    std::sort(files.begin(), files.end());
    for (const auto& [time, path] : files) {
      const std::string rel = fs::relative(path, dir_).generic_string();
      const uint64_t size = fs::file_size(path, ec);
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
    std::unique_lock lock(mutex_);
    if (auto it = entries_.find(rel); it != entries_.end()) {
      order_.splice(order_.begin(), order_, it->second.position);
      lock.unlock();
      auto bytes = read_file(dir_ / rel);
      if (bytes && tiles::StoreSource::verify(rel, *bytes)) {
        std::lock_guard relock(mutex_);
        ++hits_;
        return bytes;
      }
      lock.lock();  // missing or damaged: forget it and fetch anew
      ++repaired_;
      drop_locked(rel);
    }
    // One upstream fetch per file at a time; others wait for its result.
    if (auto it = in_flight_.find(rel); it != in_flight_.end()) {
      auto flight = it->second;
      ++shared_;
      ready_.wait(lock, [&] { return flight->done; });
      if (flight->result) return flight->result;
      return std::unexpected(flight->result.error());
    }
    auto flight = std::make_shared<Flight>();
    in_flight_[rel] = flight;
    ++misses_;
    lock.unlock();
    Result<std::vector<std::byte>> result = upstream_->fetch(rel);
    if (result) {
      std::error_code ec;
      fs::create_directories((dir_ / rel).parent_path(), ec);
      if (write_file_atomic(dir_ / rel, *result)) {
        std::lock_guard relock(mutex_);
        order_.push_front(rel);
        entries_[rel] = {result->size(), order_.begin()};
        bytes_ += result->size();
        evict_locked();
      }
    }
    lock.lock();
    flight->result = result;
    flight->done = true;
    in_flight_.erase(rel);
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
    while (bytes_ > budget_ && order_.size() > 1) {
      drop_locked(order_.back());
      ++evictions_;
    }
  }

  std::shared_ptr<const tiles::StoreSource> upstream_;
  fs::path dir_;
  uint64_t budget_;
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
    return fail(fmt::format("{}: cannot create the cache directory", directory.string()));
  }
  auto cache = std::make_shared<Cache>(std::move(upstream), directory, budget_bytes);
  cache->load_existing();
  return std::shared_ptr<DiskCache>(std::move(cache));
}

}  // namespace relief::net
