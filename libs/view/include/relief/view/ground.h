#pragma once
// The ground under the viewer: the best resident elevation of a scene at a
// longitude and latitude (never waits for I/O), and picking (a screen pixel
// to the terrain point it shows).
#include <optional>

#include "relief/lod/camera.h"
#include "relief/view/controller.h"

namespace relief::view {

class Scene;

// Heights from the finest resident tile of the scene's elevation store,
// bilinear and exaggerated as the renderer draws them (TerrainModel::bilinear
// times the scene's render exaggeration); 0 where the store has no tile.
// Interactive scenes: never waits for I/O, requests nothing and pins nothing
// beyond the query. Complete scenes (no loader) read through their terrain
// model's blocking cache, as their frames do.
// Valid while the scene lives; call on the scene's (the GL) thread.
Ground resident_ground(Scene& scene);

struct Pick {
  double lon = 0, lat = 0, height = 0;  // degrees, metres above the ellipsoid
  double distance = 0;                  // from the eye, metres
};

// The terrain point under pixel (x, y) (origin top-left) of `camera`, or
// nullopt for sky: the pixel's ray marched against `ground` in steps of half
// its height above it, then bisected to the first crossing.
std::optional<Pick> pick(const lod::Camera& camera, double x, double y, const Ground& ground);

}  // namespace relief::view
