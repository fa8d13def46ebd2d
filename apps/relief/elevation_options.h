#pragma once
// The elevation-processing options shared by `relief render` and `relief
// view` (docs/rendering.md, "Elevation operators and lenses at draw time"):
//   --elevation-op OP [--elevation-param K=V]...   (repeatable: a chain)
//   [--elevation-lens LON,LAT,RADIUS_M [--elevation-lens-op OP
//     [--elevation-lens-param K=V]...]...]...
// As the texture options, they repeat and their order matters (each param
// belongs to the op before it, each lens op to the lens before it), so they
// are taken out of the arguments before the others are parsed.
#include <string>
#include <vector>

#include "relief/base/result.h"
#include "relief/pipeline/processed_elevation.h"

namespace relief::cli {

// Removes the options from `argv` and parses them: unknown operators or
// parameters, values out of range, a param before any op, a lens op before
// any lens, a lens radius <= 0: one-line errors. Whether the operators suit
// heights and fit the store's border is checked when the store is opened
// (pipeline::check_elevation_processing).
Result<pipeline::ElevationProcessing> take_elevation_processing(std::vector<std::string>& argv);

// The help text of the options.
extern const char* const kElevationOptionsHelp;

}  // namespace relief::cli
