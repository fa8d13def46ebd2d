#pragma once
// What `relief serve` gives web clients beside the store's files
// (docs/web.md): terrain and raster tiles of the store as `relief render`
// draws it (--elevation layers fused, --elevation-op applied), imagery of
// an imagery store or of --imagery, and the pages of a web root.
#include <memory>
#include <string>

#include "args.h"
#include "relief/pipeline/processed_elevation.h"
#include "relief/web/web_service.h"
#include "texture_options.h"

namespace relief::cli {

// The options serve_web reads.
std::vector<OptionSpec> serve_web_options();

// The web service for STORE at `root`; null when there is nothing to serve
// (no tiles of this kind of store, no pages). `textures` (--texture, one
// layer): the imagery routes' layer, a single-band store coloured through
// its chain, range and colour map (pipeline::colour_layer).
Result<std::shared_ptr<web::WebService>> make_web_service(const Args& args, const std::string& root,
                                                          pipeline::ElevationProcessing elevation,
                                                          const TextureLayers& textures,
                                                          web::WebServiceOptions options);

}  // namespace relief::cli
