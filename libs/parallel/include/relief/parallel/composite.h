#pragma once
// Depth compositing of sort-last frames (seed 001 §4.1) and assembly of
// sort-first tiles, over a Comm. Every rank keeps, for the rows it
// composites, the nearest fragment of each pixel (reversed-Z: the greatest
// depth; on a tie the lowest rank, whose quads come first) and rank 0
// gathers the rows' colour. Power-of-two rank counts use binary swap (log2 N
// rounds of pairwise half exchanges, each rank sending about (N - 1) / N of
// its colour and depth in total); others direct send (the image cut into one
// band of rows per rank, each band sent to its rank at once: the same bytes,
// N - 1 messages per rank). Exchanged rows are compressed: pixels where the
// sender drew nothing (depth 0, the sky) are skipped as runs, so a rank
// sends only what its quads cover (sort-last ranks each cover about 1/N of
// the image); the result is the same to the bit.
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
// depth); both the same size.
void keep_nearer(Layer& into, const Layer& from);

// Rows [r0, r1) of a layer with the empty pixels (depth 0) left out:
// run lengths (skip, copy) and the copied pixels' colour and depth.
std::vector<std::byte> encode_rows(const Layer& layer, int r0, int r1);
// Composites encoded rows into `into`'s rows from `r0` on: a pixel of the
// message replaces `into`'s when nearer, or as near with `message_wins_ties`
// (skipped pixels are empty: the same sky colour on every rank). An error
// for a malformed message.
Status merge_encoded(Layer& into, int r0, int r1, std::span<const std::byte> message,
                     bool message_wins_ties);

// "binary-swap" or "direct-send": what depth_composite uses for `ranks`.
const char* compositing_method(int ranks);

// The composited image on rank 0 (empty elsewhere). Every rank passes a
// layer of the same size.
Result<std::vector<uint8_t>> depth_composite(Comm& comm, const Layer& layer);

// The assembled width x height image on rank 0 (empty elsewhere): each
// rank's `tile` of it (RGBA8, top row first) as placed by `tiles[rank]`.
Result<std::vector<uint8_t>> gather_tiles(Comm& comm, std::span<const uint8_t> tile,
                                          std::span<const lod::PixelRect> tiles, int width,
                                          int height);

}  // namespace relief::parallel
