#pragma once
// The GPU cache (L3): textures of data tiles within a byte budget, least
// recently used first out. Textures used by the current frame are pinned;
// only older ones are evicted. Render thread only (it owns the GL context).
#include <cstdint>
#include <list>
#include <optional>
#include <unordered_map>

#include "gl.h"
#include "relief/geo/tile_key.h"

namespace relief::render {

struct TextureKey {
  geo::TileKey tile;
  bool imagery = false;
  bool operator==(const TextureKey&) const = default;
};

struct TextureKeyHash {
  size_t operator()(const TextureKey& k) const {
    return geo::TileKeyHash{}(k.tile) ^ (k.imagery ? 0x9e3779b97f4a7c15ULL : 0);
  }
};

class TextureCache {
 public:
  explicit TextureCache(uint64_t budget_bytes) : budget_(budget_bytes) {}
  ~TextureCache() {
    for (auto& [k, e] : entries_) glDeleteTextures(1, &e.texture);
  }
  TextureCache(const TextureCache&) = delete;
  TextureCache& operator=(const TextureCache&) = delete;

  void begin_frame() { ++frame_; }

  // The cached texture, now pinned for this frame.
  std::optional<GLuint> find(const TextureKey& key) {
    auto it = entries_.find(key);
    if (it == entries_.end()) return std::nullopt;
    it->second.frame = frame_;
    order_.splice(order_.begin(), order_, it->second.position);
    return it->second.texture;
  }

  // Takes ownership of a new texture, pinned for this frame, and evicts
  // unpinned textures while over budget.
  void insert(const TextureKey& key, GLuint texture, uint64_t bytes) {
    order_.push_front(key);
    entries_.emplace(key, Entry{texture, bytes, frame_, order_.begin()});
    used_ += bytes;
    ++uploads_;
    for (auto it = order_.end(); used_ > budget_ && it != order_.begin();) {
      --it;
      auto e = entries_.find(*it);
      if (e->second.frame == frame_) continue;
      glDeleteTextures(1, &e->second.texture);
      used_ -= e->second.bytes;
      entries_.erase(e);
      it = order_.erase(it);
      ++evicted_;
    }
  }

  uint64_t used_bytes() const { return used_; }
  uint64_t budget_bytes() const { return budget_; }
  size_t count() const { return entries_.size(); }
  uint64_t uploads() const { return uploads_; }
  uint64_t evicted() const { return evicted_; }

 private:
  struct Entry {
    GLuint texture;
    uint64_t bytes;
    uint64_t frame;  // last frame that used it
    std::list<TextureKey>::iterator position;
  };
  uint64_t budget_, used_ = 0, frame_ = 0, uploads_ = 0, evicted_ = 0;
  std::list<TextureKey> order_;
  std::unordered_map<TextureKey, Entry, TextureKeyHash> entries_;
};

}  // namespace relief::render
