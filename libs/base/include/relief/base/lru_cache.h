#pragma once
// A thread-safe least-recently-used cache with a byte budget. Values are held by
// shared_ptr, so an entry evicted while a reader still uses it stays alive for
// that reader (the shared_ptr is the pin).
#include <cstdint>
#include <functional>
#include <list>
#include <memory>
#include <mutex>
#include <unordered_map>

namespace relief {

template <class Key, class Value, class Hash = std::hash<Key>>
class LruCache {
 public:
  using Ptr = std::shared_ptr<const Value>;
  LruCache(uint64_t budget_bytes, std::function<uint64_t(const Value&)> size_of)
      : budget_(budget_bytes), size_of_(std::move(size_of)) {}

  Ptr get(const Key& key) {
    std::lock_guard lock(mutex_);
    auto it = map_.find(key);
    if (it == map_.end()) {
      ++misses_;
      return nullptr;
    }
    ++hits_;
    order_.splice(order_.begin(), order_, it->second.position);
    return it->second.value;
  }

  void put(const Key& key, Ptr value) {
    const uint64_t bytes = size_of_(*value);
    std::lock_guard lock(mutex_);
    if (auto it = map_.find(key); it != map_.end()) erase_locked(it);
    order_.push_front(key);
    map_.emplace(key, Entry{std::move(value), bytes, order_.begin()});
    used_ += bytes;
    while (used_ > budget_ && order_.size() > 1) erase_locked(map_.find(order_.back()));
  }

  uint64_t used_bytes() const {
    std::lock_guard lock(mutex_);
    return used_;
  }
  uint64_t budget_bytes() const { return budget_; }
  uint64_t hits() const {
    std::lock_guard lock(mutex_);
    return hits_;
  }
  uint64_t misses() const {
    std::lock_guard lock(mutex_);
    return misses_;
  }

 private:
  struct Entry {
    Ptr value;
    uint64_t bytes;
    typename std::list<Key>::iterator position;
  };
  void erase_locked(typename std::unordered_map<Key, Entry, Hash>::iterator it) {
    used_ -= it->second.bytes;
    order_.erase(it->second.position);
    map_.erase(it);
  }

  uint64_t budget_;
  std::function<uint64_t(const Value&)> size_of_;
  mutable std::mutex mutex_;
  std::list<Key> order_;
  std::unordered_map<Key, Entry, Hash> map_;
  uint64_t used_ = 0, hits_ = 0, misses_ = 0;
};

}  // namespace relief
