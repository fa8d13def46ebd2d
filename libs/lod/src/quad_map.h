#pragma once
// An open-addressing hash map from quad keys to small values, for level-of-
// detail selection: a few thousand leaves, probed ~100 000 times per frame.
// Linear probing over packed keys, tombstones for erased entries, no
// allocation per insert.
#include <algorithm>
#include <cstdint>
#include <vector>

#include "relief/geo/tile_key.h"

namespace relief::lod {

template <class Value>
class QuadMap {
 public:
  explicit QuadMap(size_t capacity_hint = 4096) { rehash(capacity_hint * 2); }

  size_t size() const { return size_; }

  // Empties the map, keeping its slots (no allocation on the next fills).
  void clear() {
    std::fill(keys_.begin(), keys_.end(), kEmpty);
    size_ = used_ = 0;
  }

  Value* find(const geo::TileKey& k) {
    const uint64_t p = pack(k);
    for (size_t i = slot(p);; i = (i + 1) & mask_) {
      if (keys_[i] == p) return &values_[i];
      if (keys_[i] == kEmpty) return nullptr;
    }
  }
  bool contains(const geo::TileKey& k) { return find(k) != nullptr; }

  void set(const geo::TileKey& k, const Value& v) {
    if (Value* found = find(k)) {
      *found = v;
      return;
    }
    if ((used_ + 1) * 2 > keys_.size()) rehash(keys_.size() * 2);
    const uint64_t p = pack(k);
    size_t i = slot(p);
    while (keys_[i] != kEmpty && keys_[i] != kTombstone) i = (i + 1) & mask_;
    if (keys_[i] == kEmpty) ++used_;
    keys_[i] = p;
    values_[i] = v;
    ++size_;
  }

  void erase(const geo::TileKey& k) {
    const uint64_t p = pack(k);
    for (size_t i = slot(p);; i = (i + 1) & mask_) {
      if (keys_[i] == kEmpty) return;
      if (keys_[i] == p) {
        keys_[i] = kTombstone;
        --size_;
        return;
      }
    }
  }

  // Keys packed into 64 bits, ordered as TileKey's comparison orders them
  // (level, x, y).
  static uint64_t pack(const geo::TileKey& k) {
    return static_cast<uint64_t>(k.level) << 58 | static_cast<uint64_t>(k.x) << 29 | k.y;
  }
  static geo::TileKey unpack(uint64_t p) {
    return {static_cast<int>(p >> 58), static_cast<uint32_t>((p >> 29) & ((1u << 29) - 1)),
            static_cast<uint32_t>(p & ((1u << 29) - 1))};
  }

  template <class F>
  void for_each(F f) const {
    for (size_t i = 0; i < keys_.size(); ++i) {
      if (keys_[i] != kEmpty && keys_[i] != kTombstone) f(unpack(keys_[i]), values_[i]);
    }
  }

 private:
  static constexpr uint64_t kEmpty = ~uint64_t{0}, kTombstone = ~uint64_t{0} - 1;
  size_t slot(uint64_t p) const {
    p ^= p >> 33;
    p *= 0xff51afd7ed558ccdULL;
    p ^= p >> 33;
    return static_cast<size_t>(p) & mask_;
  }
  void rehash(size_t want) {
    size_t n = 16;
    while (n < want) n *= 2;
    std::vector<uint64_t> old_keys(n, kEmpty);
    std::vector<Value> old_values(n);
    old_keys.swap(keys_);
    old_values.swap(values_);
    mask_ = n - 1;
    size_ = used_ = 0;
    for (size_t i = 0; i < old_keys.size(); ++i) {
      if (old_keys[i] != kEmpty && old_keys[i] != kTombstone)
        set(unpack(old_keys[i]), old_values[i]);
    }
  }

  std::vector<uint64_t> keys_;
  std::vector<Value> values_;
  size_t mask_ = 0, size_ = 0, used_ = 0;  // used_: live entries and tombstones
};

}  // namespace relief::lod
