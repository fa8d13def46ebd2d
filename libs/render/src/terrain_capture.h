#pragma once
// For tests: the vertices a frame would draw, read back with transform
// feedback instead of rasterised.
#include <vector>

#include "relief/render/terrain_renderer.h"

namespace relief::render {

// Every vertex of every triangle the frame draws, in draw order (quad by quad,
// triangle by triangle): x, y, z relative to the eye in metres, with heights,
// exactly as the vertex shader computes them.
Result<std::vector<float>> capture_positions(TerrainRenderer& renderer, const lod::View& view,
                                             const lod::Selection& selection,
                                             const RenderOptions& options,
                                             const lod::RefinedMesh* refined = nullptr);

}  // namespace relief::render
