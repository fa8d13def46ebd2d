#pragma once
// A camera path: keyframes in time, interpolated for each frame. Used by
// `relief render --path` and by the benchmarks of streaming.
#include <span>
#include <vector>

#include "relief/lod/camera.h"

namespace relief::lod {

struct Keyframe {
  double time = 0;  // seconds, increasing
  Camera camera;
  bool cut = false;  // jumped to at `time`: the camera holds the previous keyframe until then
};

// The camera at time t: linear between the keyframes around t (heading the
// short way round, longitude across the antimeridian likewise), clamped to
// the first and last.
Camera camera_at(std::span<const Keyframe> path, double t);

}  // namespace relief::lod
