#include "tile_slots.h"

#include <algorithm>

#include <fmt/format.h>

#include "height_slopes.h"

namespace relief::render {

TileSlots::TileSlots(uint64_t budget_bytes, int max_layers)
    : budget_(budget_bytes),
      max_layers_(max_layers),
      heights_(GL_R32F, GL_RED, GL_FLOAT, 4),
      slopes_(GL_RG16F, GL_RG, GL_HALF_FLOAT, 4),
      imagery_(GL_RGBA8, GL_RGBA, GL_UNSIGNED_BYTE, 4) {}

uint64_t TileSlots::allocated_bytes() const {
  return static_cast<uint64_t>(heights_.layers()) *
             (heights_.layer_bytes() + slopes_.layer_bytes()) +
         static_cast<uint64_t>(imagery_.layers()) * imagery_.layer_bytes();
}

std::optional<int> TileSlots::find(const TextureKey& key) {
  auto it = entries_.find(key);
  if (it == entries_.end()) return std::nullopt;
  if (it->second.frame != frame_) ++pool(key.imagery).pinned;
  it->second.frame = frame_;
  order_.splice(order_.begin(), order_, it->second.position);
  announce_growth_ahead(key.imagery, false);  // a frame of resident tiles pins them here
  return it->second.layer;
}

bool TileSlots::evict_one(std::optional<bool> imagery) {
  for (auto it = order_.end(); it != order_.begin();) {
    --it;
    if (imagery && it->imagery != *imagery) continue;
    auto e = entries_.find(*it);
    if (e->second.frame == frame_) continue;
    pool(it->imagery).free.push_back(e->second.layer);
    used_ -= e->second.bytes;
    entries_.erase(e);
    order_.erase(it);
    ++evicted_;
    return true;
  }
  return false;
}

uint64_t TileSlots::layer_bytes(bool imagery) const {
  return imagery ? imagery_.layer_bytes() : heights_.layer_bytes() + slopes_.layer_bytes();
}

int TileSlots::next_layers(bool imagery, int old, uint64_t layer_bytes) const {
  // Double, but not past what the budget holds beside the other kind's
  // arrays unless the frame needs it.
  const gl::TextureArray& other = imagery ? heights_ : imagery_;
  const uint64_t other_bytes = static_cast<uint64_t>(other.layers()) * this->layer_bytes(!imagery);
  const uint64_t room = budget_ > other_bytes ? budget_ - other_bytes : 0;
  const int fits = static_cast<int>(std::min<uint64_t>(room / layer_bytes, uint64_t(max_layers_)));
  int layers = old == 0 ? kFirstLayers : old * 2;
  if (layers > fits) layers = std::max(fits, old + 16);
  return std::min(layers, max_layers_);
}

void TileSlots::announce_growth_ahead(bool imagery, bool composite) {
  Pool p = pool(imagery);
  const int layers = p.array.layers();
  int& announced = imagery ? announced_imagery_ : announced_heights_;
  if (!on_growth_ahead_ || announced == layers) return;
  // Uploaded tiles grow a full array once a frame pins half its layers
  // (insert()), composites whenever it is full.
  const int in_use = layers - static_cast<int>(p.free.size());
  if (composite ? 4 * in_use < 3 * layers : 8 * p.pinned < 3 * layers) return;
  announced = layers;
  const int next = next_layers(imagery, layers, layer_bytes(imagery));
  // Not a growth past what the budget holds: only a frame that needs more
  // makes one, and memory faulted in for it would mostly wait in vain.
  if (next < 2 * layers) return;
  on_growth_ahead_(static_cast<uint64_t>(next) * p.array.layer_bytes());
  if (!imagery) on_growth_ahead_(static_cast<uint64_t>(next) * slopes_.layer_bytes());
}

void TileSlots::grow(bool imagery, uint64_t layer_bytes) {
  Pool p = pool(imagery);
  const int old = p.array.layers();
  const int layers = next_layers(imagery, old, layer_bytes);
  p.array.reserve(layers);
  if (!imagery) slopes_.reserve(layers);
  for (int l = layers - 1; l >= old; --l) p.free.push_back(l);
}

void TileSlots::allocate(bool imagery, int width, int height) {
  Pool p = pool(imagery);
  if (p.array.sized()) return;
  p.array.set_layer_size(width, height);
  if (!imagery) slopes_.set_layer_size(width, height);
  grow(imagery, layer_bytes(imagery));
}

Result<int> TileSlots::insert(const TextureKey& key, int width, int height, const void* pixels,
                              gl::Uploads& uploads) {
  Pool p = pool(key.imagery);
  if (!p.array.sized()) p.array.set_layer_size(width, height);
  if (width != p.array.width() || height != p.array.height()) {
    return fail(fmt::format("tile {} is {}x{}, the store's others {}x{}", key.tile.to_string(),
                            width, height, p.array.width(), p.array.height()));
  }
  if (!key.imagery && !slopes_.sized()) slopes_.set_layer_size(width, height);
  const uint64_t bytes = layer_bytes(key.imagery);
  while (used_ + bytes > budget_ && evict_one(std::nullopt)) {
  }
  if (p.free.empty() && p.array.layers() >= max_layers_ && !evict_one(key.imagery)) {
    return fail(fmt::format(
        "the frame needs more than {} {} tiles on the GPU at once (GL_MAX_ARRAY_TEXTURE_LAYERS)",
        max_layers_, key.imagery ? "imagery" : "elevation"));
  }
  // Full, with fewer than half its layers pinned: a layer is reused rather
  // than every layer copied into a larger array (uploaded tiles only).
  if (p.free.empty() && pixels && 2 * p.pinned < p.array.layers()) evict_one(key.imagery);
  if (p.free.empty()) grow(key.imagery, bytes);
  const int layer = p.free.back();
  p.free.pop_back();
  if (pixels) p.array.upload(layer, pixels, uploads);
  if (pixels && !key.imagery) {
    const std::vector<uint16_t> slopes = height_slopes(
        {static_cast<const float*>(pixels), static_cast<size_t>(width) * height}, width, height);
    slopes_.upload(layer, slopes.data(), uploads);
  }
  order_.push_front(key);
  entries_.emplace(key, Entry{layer, bytes, frame_, order_.begin()});
  used_ += bytes;
  ++uploads_;
  ++p.pinned;
  announce_growth_ahead(key.imagery, !pixels);
  return layer;
}

}  // namespace relief::render
