#pragma once
// The screen-space guarantee checked brute force over a store presented at
// draw time (fused or processed elevation layers: pipeline/fused_elevation.h,
// pipeline/processed_elevation.h): every finest sample of the store, at its
// place, projects within the pixel error of the drawn mesh, as
// error_bound_test and refine_test check a built store.
#include <optional>
#include <span>

#include "relief/lod/camera.h"
#include "relief/lod/terrain_model.h"
#include "relief/tiles/store.h"

namespace relief::lod {

struct GuaranteeCase {
  Camera camera;
  double pixel_error;
};

// A finest sample near (lon, lat) and its height; nullopt without data.
struct FinestSample {
  double lon, lat;
  float h;
};
std::optional<FinestSample> finest_sample(const tiles::Store& store, TerrainModel& terrain,
                                          double lon, double lat);

// Whether a finest sample lies within two samples of `level` of the data's
// outer edge (the store's extent), where the stencils of that level's full
// mesh hold nodata: the geometric error leaves such samples out
// (docs/store-format.md, "Nodata and the data's edge"), and the mesh there
// falls off to the ellipsoid.
bool near_data_edge(const tiles::Store& store, const FinestSample& s, int level);

// Quads (--lod quads): `samples_per_quad` random finest samples under each
// selected quad, each within the case's pixel error of the quad's mesh.
void expect_quads_keep_the_guarantee(const tiles::Store& store,
                                     std::span<const GuaranteeCase> cases,
                                     int samples_per_quad = 40);

// Edge marks (the default --lod), with the frame loop's split feedback.
void expect_refined_meshes_keep_the_guarantee(const tiles::Store& store,
                                              std::span<const GuaranteeCase> cases,
                                              int samples_per_quad = 400);

}  // namespace relief::lod
