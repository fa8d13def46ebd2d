#pragma once
// The texture-layer options shared by `relief render` and `relief view`
// (one parser): per layer
//   --texture STORE [--texture-op OP [--texture-param K=V]...]...
//   [--texture-range MIN,MAX] [--texture-opacity A] [--texture-colormap NAME]
//   [--lens LON,LAT,RADIUS_M [--lens-op OP [--lens-param K=V]...]...]...
// and once, for every layer, --process-on gpu|cpu|auto.
// They repeat and their order matters (each --texture-op and its
// --texture-param belong to the --texture before them), so they are taken out
// of the arguments before the others are parsed.
#include <deque>
#include <string>
#include <vector>

#include "relief/base/result.h"
#include "relief/render/terrain_renderer.h"
#include "relief/tiles/store.h"

namespace relief::cli {

struct TextureLayers {
  std::deque<tiles::Store> stores;           // what the layers point to (stable addresses)
  std::vector<render::TextureLayer> layers;  // bottom first, checked
  std::vector<std::string> paths;            // of the stores, for the output checks
};

// Removes the texture options from `argv` and opens and checks every layer:
// unknown operators or parameters, values out of range, a --texture-param or
// --texture-op before any --texture (or a param before any op), an operator
// not valid for the store's kind, a chain wider than the store's border, a
// range with min >= max, an opacity outside [0, 1], a lens radius <= 0:
// one-line errors.
Result<TextureLayers> take_texture_layers(std::vector<std::string>& argv);

// Operators as given, each with its "key=value" parameters.
using OperatorTexts = std::vector<std::pair<std::string, std::vector<std::string>>>;
// The chain of `ops` (unknown operators, parameters out of range: one-line
// errors starting with `option` and the operator).
Result<gpuprocess::OperatorChain> make_chain(const char* option, const OperatorTexts& ops);

// A lens's LON,LAT,RADIUS_M (longitude in [-180, 360), normalised to
// [-180, 180]; radius > 0), errors starting with `option`.
struct LensCircle {
  double lon = 0, lat = 0, radius_m = 0;
};
Result<LensCircle> parse_lens_circle(const char* option, const std::string& text);

// The help text of the options.
extern const char* const kTextureOptionsHelp;

}  // namespace relief::cli
