#pragma once
// Camera paths on disk: the JSON that `relief render --path` and
// `relief view --play` read and the viewer's recorder writes.
//
//   {"fps": N, "keyframes": [{"time": T, "camera": [lon, lat, height,
//                              heading, pitch, roll], "cut": bool}, ...]}
//
// Numbers are written so they read back bit for bit (a recorded flight
// plays back exactly).
#include <cstddef>
#include <cstdint>
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

// A path file holds keyframes of about 150 bytes: 32 MiB is over 200 000 of
// them, a recorded hour at 60 fps. A larger file is refused before it is read.
inline constexpr uint64_t kMaxPathFileBytes = uint64_t{32} << 20;
// Frames per second a path may ask for: a frame is drawn at least every second
// (a path at 1e-9 fps would wait 30 years for its second frame).
inline constexpr double kMinPathFps = 1;
inline constexpr double kMaxPathFps = 1000;

// The number of frames of `keyframes` at `fps`, or an error naming `where` if
// more than `max_frames` (a keyframe at 1e12 s must not play or render until
// killed; --max-frames raises the limit).
inline constexpr int kDefaultMaxFrames = 100000;
Result<size_t> count_path_frames(const std::vector<lod::Keyframe>& keyframes, double fps,
                                 int max_frames, const std::string& where);

std::string path_to_json(const PathFile& path);
// Atomic: the file is complete or not there.
Status write_path_file(const std::string& path, const PathFile& file);

}  // namespace relief::view
