#include "serve_web.h"

#include <fmt/format.h>

#include <cstdio>

#include "relief/pipeline/coloured_layer.h"
#include "relief/tiles/store.h"
#include "render_setup.h"

namespace relief::cli {

std::vector<OptionSpec> serve_web_options() {
  return {{"--elevation"}, {"--fuse"}, {"--weights"}, {"--imagery"}};
}

namespace {

Result<std::shared_ptr<const web::RasterTiler>> raster_tiler(
    std::shared_ptr<const tiles::Store> s) {
  auto tiler = RELIEF_TRY(web::RasterTiler::create(std::move(s)));
  return std::make_shared<const web::RasterTiler>(std::move(tiler));
}

// The imagery of a --texture layer: an RGBA store as it is, a single-band
// one coloured as relief render drapes it.
Result<tiles::Store> texture_imagery(const TextureLayers& textures) {
  if (textures.layers.size() != 1) {
    return fail(fmt::format("--texture: the web routes serve one layer; {} were given",
                            textures.layers.size()));
  }
  const render::TextureLayer& layer = textures.layers.front();
  if (!layer.lenses.empty()) return fail("--lens: lenses are not served to web clients yet");
  if (layer.store->manifest().kind == tiles::DatasetKind::Imagery) return *layer.store;
  return pipeline::colour_layer(*layer.store, textures.paths.front(),
                                {layer.chain, layer.range_min, layer.range_max, layer.colormap});
}

// The tiles of STORE (and --imagery or --texture) for web clients.
Result<web::WebLayers> layers_of(const Args& args, const std::string& root,
                                 pipeline::ElevationProcessing elevation,
                                 const TextureLayers& textures) {
  web::WebLayers layers;
  std::shared_ptr<const tiles::Store> imagery_store;
  tiles::Store plain = RELIEF_TRY(open_store(root));
  const auto kind = plain.manifest().kind;
  if (kind == tiles::DatasetKind::Elevation) {
    auto store = std::make_shared<const tiles::Store>(
        RELIEF_TRY(open_elevation(args, root, std::move(elevation))));
    layers.terrain =
        std::make_shared<const web::TerrainTiler>(RELIEF_TRY(web::TerrainTiler::create(store)));
    layers.dem = RELIEF_TRY(raster_tiler(store));
  } else if (!args.get_all("--elevation").empty() || !elevation.empty()) {
    return fail(
        fmt::format("serve: {} holds {}: --elevation and --elevation-op need an "
                    "elevation STORE",
                    root, tiles::to_string(kind)));
  } else if (kind == tiles::DatasetKind::Imagery) {
    imagery_store = std::make_shared<const tiles::Store>(std::move(plain));
  }
  if (auto imagery = args.get("--imagery")) {
    if (imagery_store) return fail("--imagery: STORE already holds the imagery served");
    tiles::Store store = RELIEF_TRY(open_store(*imagery));
    if (store.manifest().kind != tiles::DatasetKind::Imagery) {
      return fail(fmt::format("--imagery: {} holds {} data, not imagery", *imagery,
                              tiles::to_string(store.manifest().kind)));
    }
    imagery_store = std::make_shared<const tiles::Store>(std::move(store));
  }
  if (!textures.layers.empty()) {
    if (imagery_store) {
      return fail("--texture: the imagery is served already (an imagery STORE or --imagery)");
    }
    imagery_store = std::make_shared<const tiles::Store>(RELIEF_TRY(texture_imagery(textures)));
  }
  if (imagery_store) {
    layers.imagery = RELIEF_TRY(raster_tiler(imagery_store));
    // Cesium's geographic tiling where the imagery's tiles allow it (512 x 256).
    if (auto g = web::GeographicTiles::create(imagery_store)) {
      layers.imagery_geographic = std::make_shared<const web::GeographicTiles>(std::move(*g));
    }
  }
  return layers;
}

}  // namespace

Result<std::shared_ptr<web::WebService>> make_web_service(const Args& args, const std::string& root,
                                                          pipeline::ElevationProcessing elevation,
                                                          const TextureLayers& textures,
                                                          web::WebServiceOptions options) {
  const bool layer_options = !args.get_all("--elevation").empty() || !elevation.empty() ||
                             args.get("--imagery").has_value() || !textures.layers.empty();
  auto layers = layers_of(args, root, std::move(elevation), textures);
  if (!layers) {
    // Asked for: an error. Otherwise the store's files are still served as
    // they are (a client may need them to learn what is wrong, e.g. a store
    // to upgrade, or tiles of a size web tiles are not made from).
    if (layer_options) return std::unexpected(layers.error());
    std::fprintf(stderr, "relief serve: no web tiles: %s\n", layers.error().message.c_str());
    layers = web::WebLayers{};
  }
  if (!layers->terrain && !layers->dem && !layers->imagery && options.pages.empty()) {
    return nullptr;
  }
  return std::make_shared<web::WebService>(std::move(*layers), std::move(options));
}

}  // namespace relief::cli
