#include "elevation_options.h"

#include <fmt/format.h>

#include "texture_options.h"

namespace relief::cli {

const char* const kElevationOptionsHelp =
    R"(elevation processed at draw time (docs/rendering.md):
  --elevation-op OP  smooth the (fused) heights when read: mean, gauss or median
                     (the operators valid for heights); repeat for a chain,
                     applied in the order given; its radii must fit the
                     store's border less 2 (7 samples of the default 9)
  --elevation-param K=V  a parameter of the --elevation-op before it (the
                     finest level's; coarser levels scale masks to the same
                     ground size)
  --elevation-lens LON,LAT,RADIUS_M  inside the circle the heights go through
                     the --elevation-lens-op chain instead (per sample:
                     crack-free at the circle); repeatable, the last wins
  --elevation-lens-op OP, --elevation-lens-param K=V  the lens's chain
                     (none: the unprocessed heights inside the circle)
                     Opening processes every tile once for the exact
                     geometric errors of the processed pyramid.
)";

namespace {

struct ElevationLensText {
  std::string where;
  OperatorTexts ops;
};

}  // namespace

Result<pipeline::ElevationProcessing> take_elevation_processing(std::vector<std::string>& argv) {
  std::vector<std::string> rest;
  OperatorTexts ops;
  std::vector<ElevationLensText> lenses;
  for (size_t i = 0; i < argv.size(); ++i) {
    std::string name = argv[i], value;
    if (auto eq = name.find('='); name.starts_with("--") && eq != std::string::npos) {
      value = name.substr(eq + 1), name = name.substr(0, eq);
    } else if (name == "--elevation-op" || name == "--elevation-param" ||
               name == "--elevation-lens" || name == "--elevation-lens-op" ||
               name == "--elevation-lens-param") {
      if (i + 1 == argv.size()) return fail(fmt::format("option {} needs a value", name));
      value = argv[++i];
    }
    if (name == "--elevation-op") {
      ops.push_back({value, {}});
    } else if (name == "--elevation-param") {
      if (ops.empty()) {
        return fail(fmt::format("--elevation-param {}: comes before any --elevation-op", value));
      }
      ops.back().second.push_back(value);
    } else if (name == "--elevation-lens") {
      lenses.push_back({value, {}});
    } else if (name == "--elevation-lens-op") {
      if (lenses.empty()) {
        return fail(
            fmt::format("--elevation-lens-op {}: comes before any --elevation-lens", value));
      }
      lenses.back().ops.push_back({value, {}});
    } else if (name == "--elevation-lens-param") {
      if (lenses.empty() || lenses.back().ops.empty()) {
        return fail(
            fmt::format("--elevation-lens-param {}: comes before any --elevation-lens-op", value));
      }
      lenses.back().ops.back().second.push_back(value);
    } else {
      rest.push_back(argv[i]);
    }
  }
  pipeline::ElevationProcessing p;
  p.chain = RELIEF_TRY(make_chain("--elevation-op", ops));
  for (const ElevationLensText& t : lenses) {
    const LensCircle c = RELIEF_TRY(parse_lens_circle("--elevation-lens", t.where));
    pipeline::ElevationLens lens{c.lon, c.lat, c.radius_m, {}};
    lens.chain = RELIEF_TRY(make_chain("--elevation-lens-op", t.ops));
    p.lenses.push_back(std::move(lens));
  }
  argv = std::move(rest);
  return p;
}

}  // namespace relief::cli
