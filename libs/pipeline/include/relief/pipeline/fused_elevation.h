#pragma once
// Elevation layers fused at draw time (issue 14): several elevation stores
// presented as one store, whose tiles are fused when read (on the reading
// thread: the tile loader's threads when drawing) by the per-tile fusion of
// `relief fuse` (fuse_tiles.h). Level-of-detail selection, the loader, the
// edge-mark refinement's diamond errors and the renderer see an ordinary
// store: nothing downstream knows the heights are fused.
//
// The level indexes are built when the layers are opened: the union of the
// layers' tiles per level, each tile's bounds from its fused samples, and the
// exact geometric errors of the fused pyramid, computed by the same code as
// `relief build` (tiles/geometric_error.h) over the fused tiles. That reads
// every fused tile once (docs/rendering.md, "Elevation layers fused at draw
// time").
#include <string>
#include <vector>

#include "relief/base/parallel.h"
#include "relief/base/result.h"
#include "relief/pipeline/fuse_tiles.h"
#include "relief/tiles/store.h"

namespace relief::pipeline {

struct ElevationLayer {
  std::string name;  // for messages: the path or URL it was opened from
  tiles::Store store;
};

// At least one layer, every one an elevation store of the same tile size and
// border (the first is the reference; an error names the layer that
// differs). First: the first layer with a valid sample wins, the deeper
// layers first, then in the order given; Blend: the mean of the valid
// samples, weighted by `weights` (one per layer in the order given, each > 0;
// empty: all 1) exactly as `relief fuse --weights` weighs its inputs
// (fuse_weights()). Below a layer's finest level its finest tiles are
// upsampled (bilinear). Layers of different depths make a store of sparse
// depth (Manifest::sparse_depth): where a tile has no child, quads below it
// draw it.
Result<tiles::Store> fuse_elevation_layers(std::vector<ElevationLayer> layers, FuseMode mode,
                                           Executor& executor, std::vector<double> weights = {});

}  // namespace relief::pipeline
