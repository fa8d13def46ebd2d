#include "relief/web/web_service.h"

#include <atomic>
#include <condition_variable>
#include <functional>
#include <mutex>
#include <set>
#include <utility>

#include <fmt/format.h>

#include "relief/base/lru_cache.h"
#include "relief/web/tile_path.h"

namespace relief::web {
namespace {

// A tile of one route.
struct TileRequest {
  int route = 0;
  int z = 0;
  uint32_t x = 0, y = 0;
  auto operator<=>(const TileRequest&) const = default;
};
struct TileRequestHash {
  size_t operator()(const TileRequest& t) const {
    return std::hash<uint64_t>{}((uint64_t{t.x} << 32 | t.y) * 131 +
                                 static_cast<uint64_t>(t.z * 8 + t.route));
  }
};

// One generation per tile at a time: the first request makes it, the
// others wait for it instead of making it again.
class InFlight {
 public:
  using Body = std::shared_ptr<const std::string>;
  Body get_or_make(const TileRequest& key, const std::function<Body()>& make) {
    std::unique_lock lock(mutex_);
    done_.wait(lock, [&] { return !pending_.contains(key); });
    pending_.insert(key);
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
  std::set<TileRequest> pending_;
};

// A tile route: "/prefix/{z}/{x}/{y}.ext", its description file, and how
// its tiles are made.
struct Route {
  std::string prefix, extension, description_name, description;
  std::string content_type, content_encoding;
  std::function<bool(int, uint32_t, uint32_t)> available;
  std::function<Result<std::vector<std::byte>>(int, uint32_t, uint32_t)> make;
};

std::vector<Route> routes_of(const WebLayers& layers, const std::string& name) {
  std::vector<Route> routes;
  if (const auto t = layers.terrain) {
    routes.push_back({"/terrain/", ".terrain", "layer.json", t->layer_json(name),
                      "application/vnd.quantized-mesh", "gzip",
                      [t](int z, uint32_t x, uint32_t y) {
                        return t->available({z, x, y});
                      },
                      [t](int z, uint32_t x, uint32_t y) {
                        return t->tile({z, x, y});
                      }});
  }
  if (const auto d = layers.dem) {
    for (const DemEncoding e : {DemEncoding::TerrainRgb, DemEncoding::Terrarium}) {
      routes.push_back({fmt::format("/{}/", format_name(e)), ".png", "tiles.json",
                        d->tile_json(name, e), "image/png", "",
                        [d](int z, uint32_t x, uint32_t y) {
                          return d->available({z, x, y});
                        },
                        [d, e](int z, uint32_t x, uint32_t y) {
                          return d->dem_png_tile({z, x, y}, e);
                        }});
    }
  }
  if (const auto im = layers.imagery) {
    // Before /imagery/, whose prefix it extends.
    routes.push_back({"/imagery/webp/", ".webp", "tiles.json",
                      im->tile_json(name, std::nullopt, "webp"), "image/webp", "",
                      [im](int z, uint32_t x, uint32_t y) {
                        return im->available({z, x, y});
                      },
                      [im](int z, uint32_t x, uint32_t y) {
                        return im->imagery_webp_tile({z, x, y});
                      }});
    routes.push_back({"/imagery/", ".png", "tiles.json", im->tile_json(name, std::nullopt),
                      "image/png", "",
                      [im](int z, uint32_t x, uint32_t y) {
                        return im->available({z, x, y});
                      },
                      [im](int z, uint32_t x, uint32_t y) {
                        return im->imagery_png_tile({z, x, y});
                      }});
  }
  if (const auto g = layers.imagery_geographic) {
    routes.push_back({"/imagery-geo/", ".png", "tiles.json", g->description(name), "image/png", "",
                      [g](int z, uint32_t x, uint32_t y) {
                        return g->available({z, x, y});
                      },
                      [g](int z, uint32_t x, uint32_t y) {
                        return g->png_tile({z, x, y});
                      }});
  }
  return routes;
}

}  // namespace

struct WebService::Impl {
  WebServiceOptions options;
  std::vector<Route> routes;
  mutable LruCache<TileRequest, std::string, TileRequestHash> tiles;
  mutable InFlight in_flight;
  mutable std::atomic<uint64_t> made{0};
  StaticFiles pages;

  Impl(const WebLayers& layers, WebServiceOptions o)
      : options(std::move(o)),
        routes(routes_of(layers, options.name)),
        tiles(options.cache_bytes, [](const std::string& s) { return s.size() + 64; }),
        pages(options.pages) {}

  // The route whose prefix `path` starts with, and the path after it.
  std::optional<std::pair<int, std::string_view>> route_of(std::string_view path) const {
    for (size_t i = 0; i < routes.size(); ++i) {
      if (path.starts_with(routes[i].prefix)) {
        return std::pair{static_cast<int>(i), path.substr(routes[i].prefix.size())};
      }
    }
    return std::nullopt;
  }

  // The route's layer.json or tiles.json, when `rest` names it.
  std::optional<WebAnswer> description(int index, std::string_view rest) const {
    const Route& route = routes[static_cast<size_t>(index)];
    if (rest != route.description_name) return std::nullopt;
    return WebAnswer{"application/json", "", route.description};
  }

  std::optional<WebAnswer> tile(int index, std::string_view rest) const {
    const Route& route = routes[static_cast<size_t>(index)];
    const auto path = parse_tile_path(rest, route.extension);
    if (!path || !route.available(path->z, path->x, path->y)) return std::nullopt;
    const TileRequest key{index, path->z, path->x, path->y};
    auto body = tiles.get(key);
    if (!body) {
      body = in_flight.get_or_make(key, [&]() -> InFlight::Body {
        // Another request may have made it while this one waited.
        if (auto hit = tiles.get(key)) return hit;
        auto bytes = route.make(key.z, key.x, key.y);
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
    return WebAnswer{route.content_type, route.content_encoding, *body};
  }
};

WebService::WebService(WebLayers layers, WebServiceOptions options)
    : impl_(std::make_unique<Impl>(layers, std::move(options))) {}
WebService::WebService(std::shared_ptr<const TerrainTiler> terrain, WebServiceOptions options)
    : WebService(WebLayers{std::move(terrain), nullptr, nullptr, nullptr}, std::move(options)) {}
WebService::~WebService() = default;

std::optional<WebAnswer> WebService::answer(std::string_view target) const {
  const std::string_view path = target_path(target);
  const auto found = impl_->route_of(path);
  if (!found) return impl_->pages.answer(path);
  const auto [index, rest] = *found;
  if (auto d = impl_->description(index, rest)) return d;
  return impl_->tile(index, rest);
}

std::optional<WebAnswer> WebService::answer_if_made(std::string_view target) const {
  const auto found = impl_->route_of(target_path(target));
  if (!found) return std::nullopt;
  const auto [index, rest] = *found;
  if (auto d = impl_->description(index, rest)) return d;
  const Route& route = impl_->routes[static_cast<size_t>(index)];
  const auto tile = parse_tile_path(rest, route.extension);
  if (!tile) return std::nullopt;
  const auto body = impl_->tiles.get({index, tile->z, tile->x, tile->y});
  if (!body) return std::nullopt;
  return WebAnswer{route.content_type, route.content_encoding, *body};
}

uint64_t WebService::tiles_made() const {
  return impl_->made;
}

}  // namespace relief::web
