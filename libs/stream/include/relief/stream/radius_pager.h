#pragma once
// The baseline the prioritized loader is measured against (bench/stream): a
// pager that wants every store tile within a radius of the camera, like
// Ogre's Grid2DPageStrategy, level by level. The radius at level l is
// `radius_tiles` times the tile's north-south extent, so it shrinks with
// the tiles; coarser levels and nearer tiles rank first.
#include "relief/lod/terrain_model.h"

namespace relief::stream {

// Requests (through `terrain`) every tile of the store in range of `eye`;
// returns how many.
Result<size_t> request_radius(lod::TerrainModel& terrain, const tiles::Store& store,
                              const lod::Vec3& eye, double radius_tiles);

}  // namespace relief::stream
