#include "relief/web/web_service.h"

#include <atomic>
#include <condition_variable>
#include <map>
#include <mutex>

#include "relief/base/lru_cache.h"
#include "relief/web/tile_path.h"

namespace relief::web {

namespace {

constexpr std::string_view kTerrain = "/terrain/";

// One generation per tile at a time: the first request makes it, the
// others wait for it instead of making it again.
class InFlight {
 public:
  using Body = std::shared_ptr<const std::string>;
  template <class Make>
  Body get_or_make(const TerrainKey& key, Make make) {
    std::unique_lock lock(mutex_);
    for (;;) {
      auto it = pending_.find(key);
      if (it == pending_.end()) break;
      done_.wait(lock);
    }
    pending_[key] = true;
    lock.unlock();
    Body body = make();
    lock.lock();
    pending_.erase(key);
    done_.notify_all();
    return body;
  }

 private:
  std::mutex mutex_;
  std::condition_variable done_;
  std::map<TerrainKey, bool> pending_;
};

}  // namespace

struct WebService::Impl {
  std::shared_ptr<const TerrainTiler> terrain;
  WebServiceOptions options;
  std::string layer_json;
  mutable LruCache<TerrainKey, std::string, TerrainKeyHash> tiles;
  mutable InFlight in_flight;
  mutable std::atomic<uint64_t> made{0};
  StaticFiles pages;

  Impl(std::shared_ptr<const TerrainTiler> t, WebServiceOptions o)
      : terrain(std::move(t)),
        options(std::move(o)),
        layer_json(terrain ? terrain->layer_json(options.name) : std::string()),
        tiles(options.cache_bytes, [](const std::string& s) { return s.size() + 64; }),
        pages(options.pages) {}

  std::optional<WebAnswer> terrain_tile(std::string_view rest) const {
    const auto path = parse_tile_path(rest, ".terrain");
    if (!path) return std::nullopt;
    const TerrainKey key{path->z, path->x, path->y};
    if (!terrain->available(key)) return std::nullopt;
    auto body = tiles.get(key);
    if (!body) {
      body = in_flight.get_or_make(key, [&]() -> InFlight::Body {
        // Another request may have made it while this one waited.
        if (auto hit = tiles.get(key)) return hit;
        auto bytes = terrain->tile(key);
        if (!bytes) return nullptr;
        ++made;
        auto made_body = std::make_shared<const std::string>(
            reinterpret_cast<const char*>(bytes->data()), bytes->size());
        tiles.put(key, made_body);
        return made_body;
      });
    }
    // A store tile that cannot be read: no answer rather than a wrong one.
    if (!body) return std::nullopt;
    return WebAnswer{"application/vnd.quantized-mesh", "gzip", *body};
  }
};

WebService::WebService(std::shared_ptr<const TerrainTiler> terrain, WebServiceOptions options)
    : impl_(std::make_unique<Impl>(std::move(terrain), std::move(options))) {}
WebService::~WebService() = default;

std::optional<WebAnswer> WebService::answer(std::string_view target) const {
  const std::string_view path = target_path(target);
  if (!path.starts_with(kTerrain)) return impl_->pages.answer(path);
  if (!impl_->terrain) return std::nullopt;
  const std::string_view rest = path.substr(kTerrain.size());
  if (rest == "layer.json") return WebAnswer{"application/json", "", impl_->layer_json};
  return impl_->terrain_tile(rest);
}

uint64_t WebService::tiles_made() const {
  return impl_->made;
}

}  // namespace relief::web
