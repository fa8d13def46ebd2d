#pragma once
// The hillshade's input, made once per elevation tile when it is uploaded
// (docs/rendering.md, "Shading"): per sample, the height differences across
// it, east minus west and south minus north (rows run south), with indices
// clamped to the tile as the GL clamps texels at its edges, as half floats
// (an RG16F texture layer beside the tile's R32F heights).
//
// Why it equals what the fragment shader computed from the heights: bilinear
// filtering is linear in the texels, and a shift by a whole texel keeps the
// weights, so the differences filtered at p equal the heights filtered at
// p + 1 minus the heights filtered at p - 1 (per axis). One filtered fetch
// per pixel instead of four. Half floats carry 11 significant bits: the
// shade they give differs from float32's by far less than a grey level.
#include <cstdint>
#include <span>
#include <vector>

namespace relief::render {

// Two half floats (east - west, south - north) per sample of a `width` x
// `height` tile of heights, row by row.
std::vector<uint16_t> height_slopes(std::span<const float> heights, int width, int height);

// IEEE 754 binary16 nearest to `f` (ties to even); magnitudes past the
// largest half (65504) saturate to it, NaN becomes 0.
uint16_t to_half(float f);

}  // namespace relief::render
