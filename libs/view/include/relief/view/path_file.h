#pragma once
// Camera paths on disk: the JSON that `relief render --path` and
// `relief view --play` read and the viewer's recorder writes.
//
//   {"fps": N, "keyframes": [{"time": T, "camera": [lon, lat, height,
//                              heading, pitch, roll], "cut": bool}, ...]}
//
// Numbers are written so they read back bit for bit (a recorded flight
// plays back exactly).
#include <functional>
#include <string>
#include <vector>

#include "relief/base/result.h"
#include "relief/lod/camera_path.h"

namespace relief::view {

struct PathFile {
  double fps = 30;
  std::vector<lod::Keyframe> keyframes;
};

// Turns a keyframe's six camera values into a camera (field of view and
// viewport are the caller's), or fails naming `where`.
using CameraParser =
    std::function<Result<lod::Camera>(const std::string& where, const std::vector<double>& values)>;

// Fails with a one-line message naming the file (and keyframe) for anything
// that is not a valid path: not JSON, no keyframes, times not increasing, a
// camera the parser refuses or inside the ellipsoid.
Result<PathFile> read_path_file(const std::string& path, const CameraParser& camera);
Result<PathFile> parse_path(const std::string& text, const std::string& where,
                            const CameraParser& camera);

std::string path_to_json(const PathFile& path);
// Atomic: the file is complete or not there.
Status write_path_file(const std::string& path, const PathFile& file);

}  // namespace relief::view
