#pragma once
// The output of edge-mark refinement (seed 003 ch. 3): per selected quad, an
// adaptive conforming triangulation of the quad's vertex grid, for the
// renderer to draw instead of the fixed MeshTopology.
//
// The grid of a quad has (2^(k+1) + 1) x (2^k + 1) vertices (the quad is twice
// as wide as tall in degrees), vertex (i, j) at quad-space u = i / 2^(k+1),
// v = j / 2^k (u east, v south, as MeshVertex), id grid_vertex_id(k, i, j). Its
// spacing is half a sample of the quad's data window: vertices with odd
// (i, j) are sample centres, even ones sample corners. Heights come from the
// quad's data window exactly as for MeshTopology vertices (vertices on a side
// whose neighbour is coarser take the parent window's data), so vertices shared
// by two quads are bit-identical.
#include <cstdint>
#include <vector>

#include "relief/geo/tile_key.h"
#include "relief/lod/grid_vertex_ids.h"

namespace relief::lod {

struct RefinedQuad {
  uint32_t first_index = 0;  // into RefinedMesh::indices
  uint32_t index_count = 0;  // three per triangle, same winding as MeshTopology
};

struct RefineStats {
  uint64_t marks_evaluated = 0;  // split criteria evaluated
  // RefineOptions::criteria: the diamonds whose criterion it found too near
  // the threshold to decide (evaluated here), and the time it took (seconds).
  uint64_t marks_near = 0;
  double criteria_seconds = 0;
  // With a RefineHistory: quads whose decisions were the last evaluation's
  // (the camera moved too little to change any), and the criteria that
  // evaluation computed for them.
  uint32_t quads_reused = 0;
  uint64_t marks_reused = 0;
  // The history was asleep (a fast camera): nothing reused nor recorded.
  bool history_asleep = false;
  uint64_t unresolved = 0;           // diamonds over the threshold that could not split
  double max_unresolved_pixels = 0;  // their largest projected error bound
  // Quads whose level error (TerrainModel::level_error) alone may project
  // over the threshold: they refine to their full mesh where it does.
  uint32_t too_coarse = 0;
  // Those quads, and the coarser quads whose sides stopped a split: the
  // selection should split them (and refine again) to keep the bound with
  // the fewest triangles.
  std::vector<geo::TileKey> split_wanted;
  // Data tiles whose diamond errors this frame used for the first time:
  // measured on the render thread, or prepared by the loader's threads
  // (RefineCache::prepare_on_load).
  uint32_t tiles_measured = 0, tiles_prepared = 0;
  double seconds = 0;
  double cpu_seconds = 0;  // the calling thread's CPU time (seconds is wall-clock)
};

struct RefinedMesh {
  int grid_k = 0;
  std::vector<uint32_t> indices;   // grid vertex ids
  std::vector<RefinedQuad> quads;  // parallel to Selection::quads
  RefineStats stats;

  uint32_t grid_columns() const { return (2u << grid_k) + 1; }
  uint32_t grid_rows() const { return (1u << grid_k) + 1; }
  uint64_t triangles() const { return indices.size() / 3; }
};

}  // namespace relief::lod
