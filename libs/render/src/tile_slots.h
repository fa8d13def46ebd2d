#pragma once
// The GPU cache (L3): data tiles as layers of texture arrays (elevation,
// R32F, with its hillshade slopes in an RG16F array of the same layers
// (height_slopes.h), and imagery, RGBA8) within a byte budget, least
// recently used first out. Tiles used by the current frame are pinned; only older ones are
// evicted. A tile is uploaded once when it arrives and stays resident while
// it is used. Render thread only (it owns the GL context).
//
// Growing an array reallocates it and copies every layer (on llvmpipe, on a
// loaded 2-core machine: 0.25 s from 64 to 128 layers of 530 x 274 R32F,
// 0.6-0.85 s to 256, 1.9 s to 1024; uploading one layer takes 0.1 ms), so
// arrays of uploaded tiles start at kFirstLayers and
// grow only while a frame pins at least half their layers: a full array
// otherwise reuses its least recently used unpinned layer, and a tile that
// comes back is uploaded again from the memory cache (L2), a copy of one
// layer. Arrays of composites (tiles made on the GPU, costly to remake) grow
// up to the budget as before.
#include <cstdint>
#include <functional>
#include <list>
#include <optional>
#include <unordered_map>
#include <vector>

#include "gl_backend.h"
#include "relief/base/result.h"
#include "relief/geo/tile_key.h"

namespace relief::render {

struct TextureKey {
  geo::TileKey tile;
  bool imagery = false;
  // Texture-layer composites: the layers' parameter version (an older one is
  // never found again and ages out).
  uint32_t version = 0;
  bool operator==(const TextureKey&) const = default;
};

struct TextureKeyHash {
  size_t operator()(const TextureKey& k) const {
    return geo::TileKeyHash{}(k.tile) ^ (k.imagery ? 0x9e3779b97f4a7c15ULL : 0) ^
           (static_cast<size_t>(k.version) * 0xc2b2ae3d27d4eb4fULL);
  }
};

class TileSlots {
 public:
  TileSlots(uint64_t budget_bytes, int max_layers);
  TileSlots(const TileSlots&) = delete;
  TileSlots& operator=(const TileSlots&) = delete;

  // Layers the first allocation of an array has (fewer when the budget or
  // the GL limit holds fewer).
  static constexpr int kFirstLayers = 128;

  void begin_frame() {
    ++frame_;
    pinned_heights_ = pinned_imagery_ = 0;
  }

  // Allocates the first layers of an array for tiles of `width` x `height`
  // texels ahead of the first insert(), when the tile size is known before
  // any tile arrives: on llvmpipe here that takes ~36 ms for 128 layers of
  // 146 x 82 heights and slopes, a stall the first frame need not have.
  // Nothing when the array has its size already.
  void allocate(bool imagery, int width, int height);

  // Called with the bytes an array's next growth will allocate (for heights
  // then for their slopes' array), once per size, when it draws near: a
  // frame pins 3/8 of the layers of an array of uploaded tiles (found or
  // inserted), or 3/4 of a composites' array are in use. Not for a growth
  // past what the budget holds (only a frame that needs it makes one). On
  // llvmpipe here nearly all of a growth's time (0.57-0.69 s for 128 -> 256
  // layers of 530 x 274 imagery, in one frame) is the new array's fresh
  // memory being faulted in: the caller can make that memory ready off the
  // render thread (the relief executable does, apps/relief/allocator.h).
  void set_on_growth_ahead(std::function<void(uint64_t bytes)> f) {
    on_growth_ahead_ = std::move(f);
  }

  // The layer of a resident tile, now pinned for this frame.
  std::optional<int> find(const TextureKey& key);
  // Whether a tile is resident (nothing pinned, nothing reordered).
  bool contains(const TextureKey& key) const { return entries_.contains(key); }
  // Uploads a tile of `width` x `height` texels (R32F heights, with the
  // slopes made from them, or RGBA8 colours) to a free layer, pinned for this frame, evicting
  // unpinned tiles while over budget and, when no layer is free, reusing the least recently used
  // unpinned one or growing the array (see above). Fails when the tile's size differs from the
  // store's others, or when this frame already pins every layer an array can have. Null `pixels`:
  // the caller writes the layer on the GPU (texture-layer composites).
  Result<int> insert(const TextureKey& key, int width, int height, const void* pixels,
                     gl::Uploads& uploads);

  const gl::TextureArray& heights() const { return heights_; }
  // Per layer of heights(): its tile's slopes (height_slopes.h).
  const gl::TextureArray& slopes() const { return slopes_; }
  const gl::TextureArray& imagery() const { return imagery_; }
  uint64_t used_bytes() const { return used_; }
  uint64_t allocated_bytes() const;
  uint64_t budget_bytes() const { return budget_; }
  size_t count() const { return entries_.size(); }
  int slots() const { return heights_.layers() + imagery_.layers(); }
  uint64_t uploads() const { return uploads_; }
  uint64_t evicted() const { return evicted_; }
  // Tiles of a kind the current frame has found or inserted.
  int pinned(bool imagery) const { return imagery ? pinned_imagery_ : pinned_heights_; }

 private:
  struct Entry {
    int layer;
    uint64_t bytes;
    uint64_t frame;  // last frame that used it
    std::list<TextureKey>::iterator position;
  };
  struct Pool {
    gl::TextureArray& array;
    std::vector<int>& free;
    int& pinned;
  };
  Pool pool(bool imagery) {
    return imagery ? Pool{imagery_, free_imagery_, pinned_imagery_}
                   : Pool{heights_, free_heights_, pinned_heights_};
  }
  // Bytes of one layer of a kind: imagery, or heights with their slopes.
  uint64_t layer_bytes(bool imagery) const;
  // Layers an array of `old` layers grows to: the first kFirstLayers, then
  // doubling within what the budget holds beside the other kind's arrays
  // (`layer_bytes`: of the kind's arrays).
  int next_layers(bool imagery, int old, uint64_t layer_bytes) const;
  // Adds layers to a kind's array (next_layers()), all free.
  void grow(bool imagery, uint64_t layer_bytes);
  // set_on_growth_ahead()'s call, after a tile is pinned (found or inserted).
  void announce_growth_ahead(bool imagery, bool composite);
  // Evicts the least recently used unpinned tile (of one kind, if given).
  bool evict_one(std::optional<bool> imagery);

  uint64_t budget_, used_ = 0, frame_ = 0, uploads_ = 0, evicted_ = 0;
  int max_layers_;
  int pinned_heights_ = 0, pinned_imagery_ = 0;
  std::function<void(uint64_t)> on_growth_ahead_;
  int announced_heights_ = 0, announced_imagery_ = 0;  // the layers when last announced
  gl::TextureArray heights_, slopes_, imagery_;
  std::vector<int> free_heights_, free_imagery_;
  std::list<TextureKey> order_;  // most recently used first
  std::unordered_map<TextureKey, Entry, TextureKeyHash> entries_;
};

}  // namespace relief::render
