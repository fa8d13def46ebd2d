#pragma once
// A single-band store (SAR amplitudes, heights) coloured as `relief render
// --texture` drapes it on the CPU: each tile through the layer's operator
// chain (gpuprocess::run_chain_cpu; masks scaled per level to keep their size
// on the ground), its value range and colour map (gpuprocess::map_colours_cpu,
// opacity 1), presented as an imagery store (RGBA8, a one-sample border,
// nodata transparent) whose tiles are made when read. The web routes draw
// imagery stores, so web clients get SAR this way (relief serve --texture,
// docs/web.md).
#include <string>

#include "relief/base/result.h"
#include "relief/gpuprocess/chain.h"
#include "relief/gpuprocess/composite.h"
#include "relief/tiles/store.h"

namespace relief::pipeline {

struct ColouredLayer {
  gpuprocess::OperatorChain chain;  // parameters for the store's finest level
  float range_min = 0, range_max = 1;
  gpuprocess::ColorMap colormap = gpuprocess::ColorMap::grey;
};

// Fails (a one-line error starting with `name`) for a store that is not
// Float32 single-band, a chain that does not suit it (gpuprocess::
// check_chain_for) or a range with min >= max.
Result<tiles::Store> colour_layer(tiles::Store store, const std::string& name, ColouredLayer layer);

}  // namespace relief::pipeline
