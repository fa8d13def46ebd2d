#pragma once
// Depth compositing of sort-last frames (seed 001 §4.1) and assembly of
// sort-first tiles, over a Comm. Direct send: the image is cut into one band
// of rows per rank; every rank sends each band of its colour and depth to the
// band's rank, which keeps the nearest fragment of each pixel (reversed-Z:
// the greatest depth; on a tie the lowest rank, whose quads come first), and
// rank 0 gathers the bands. Each rank sends about (N - 1) / N of its colour
// and depth plus one band of colour.
#include <cstdint>
#include <span>
#include <vector>

#include "relief/base/result.h"
#include "relief/lod/camera.h"
#include "relief/parallel/comm.h"

namespace relief::parallel {

// A rank's frame: RGBA8 and depth, top row first.
struct Layer {
  int width = 0, height = 0;
  std::vector<uint8_t> rgba;
  std::vector<float> depth;
};

// Keeps in `into` the pixels of `from` that are nearer (strictly greater
// depth), over rows [row0, row0 + rows) of both.
void keep_nearer(Layer& into, const Layer& from);

// The composited image on rank 0 (empty elsewhere). Every rank passes a
// layer of the same size.
Result<std::vector<uint8_t>> depth_composite(Comm& comm, const Layer& layer);

// The assembled width x height image on rank 0 (empty elsewhere): each
// rank's `tile` of it (RGBA8, top row first) as placed by `tiles[rank]`.
Result<std::vector<uint8_t>> gather_tiles(Comm& comm, std::span<const uint8_t> tile,
                                          std::span<const lod::PixelRect> tiles, int width,
                                          int height);

}  // namespace relief::parallel
