#include "relief/view/path_file.h"

#include <cmath>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "relief/base/file_io.h"

namespace relief::view {

using nlohmann::json;

Result<PathFile> parse_path(const std::string& text, const std::string& where_file,
                            const CameraParser& camera) {
  const std::string& path = where_file;
  json doc = json::parse(text, nullptr, false);
  if (doc.is_discarded() || !doc.is_object()) return fail(path + ": not a JSON object");
  PathFile file;
  if (doc.contains("fps")) {
    if (!doc["fps"].is_number() || !(doc["fps"].get<double>() >= kMinPathFps) ||
        !(doc["fps"].get<double>() <= kMaxPathFps)) {
      return fail(fmt::format("{}: \"fps\" must be a number in [{:g}, {:g}]", path, kMinPathFps,
                              kMaxPathFps));
    }
    file.fps = doc["fps"].get<double>();
  }
  if (!doc.contains("keyframes") || !doc["keyframes"].is_array() || doc["keyframes"].empty()) {
    return fail(path + ": needs a non-empty \"keyframes\" array");
  }
  std::vector<lod::Keyframe>& keys = file.keyframes;
  for (size_t i = 0; i < doc["keyframes"].size(); ++i) {
    const json& k = doc["keyframes"][i];
    const std::string where = fmt::format("{}: keyframe {}", path, i);
    if (!k.is_object() || !k.contains("time") || !k["time"].is_number() || !k.contains("camera") ||
        !k["camera"].is_array() || k["camera"].size() != 6) {
      return fail(where +
                  ": needs \"time\" and \"camera\": [lon, lat, height, heading, pitch, roll]");
    }
    std::vector<double> c(6);
    for (size_t j = 0; j < 6; ++j) {
      if (!k["camera"][j].is_number()) return fail(where + ": camera values must be numbers");
      c[j] = k["camera"][j].get<double>();
    }
    lod::Keyframe key;
    key.time = k["time"].get<double>();
    if (!std::isfinite(key.time)) return fail(where + ": \"time\" must be finite");
    key.camera = RELIEF_TRY(camera(where, c));
    if (k.contains("cut") && !k["cut"].is_boolean())
      return fail(where + ": \"cut\" must be true or false");
    key.cut = k.value("cut", false);
    if (!keys.empty() && !(key.time > keys.back().time)) {
      return fail(where + ": times must increase");
    }
    if (auto view = lod::make_view(key.camera); !view)
      return fail(where + ": " + view.error().message);
    keys.push_back(key);
  }
  return file;
}

Result<PathFile> read_path_file(const std::string& path, const CameraParser& camera) {
  auto bytes = RELIEF_TRY(read_file(path, kMaxPathFileBytes));
  return parse_path(std::string(reinterpret_cast<const char*>(bytes.data()), bytes.size()), path,
                    camera);
}

Result<size_t> count_path_frames(const std::vector<lod::Keyframe>& keyframes, double fps,
                                 int max_frames, const std::string& where) {
  const double duration = keyframes.back().time - keyframes.front().time;
  // In double: a huge duration must not overflow the frame count.
  const double frames = std::floor(duration * fps + 1e-9) + 1;
  if (!(frames <= max_frames)) {
    return fail(
        fmt::format("{}: {:.6g} s at {:g} fps is {:.6g} frames, more than "
                    "--max-frames {} (raise it for longer paths)",
                    where, duration, fps, frames, max_frames));
  }
  return static_cast<size_t>(frames);
}

std::string path_to_json(const PathFile& file) {
  // nlohmann writes doubles in the shortest form that reads back exactly.
  json keys = json::array();
  for (const lod::Keyframe& k : file.keyframes) {
    const lod::Camera& c = k.camera;
    json key = {{"time", k.time}, {"camera", {c.lon, c.lat, c.height, c.heading, c.pitch, c.roll}}};
    if (k.cut) key["cut"] = true;
    keys.push_back(std::move(key));
  }
  // Appended piece by piece: GCC 12 at -O3 warns (-Wrestrict) on a chain of
  // const char* + std::string&& here.
  std::string text = "{\"fps\": ";
  text += json(file.fps).dump();
  text += ", \"keyframes\": [\n";
  for (size_t i = 0; i < keys.size(); ++i) {
    text += ' ';
    text += keys[i].dump();
    text += i + 1 < keys.size() ? ",\n" : "\n";
  }
  text += "]}\n";
  return text;
}

Status write_path_file(const std::string& path, const PathFile& file) {
  const std::string text = path_to_json(file);
  return write_file_atomic(path, std::as_bytes(std::span(text.data(), text.size())));
}

}  // namespace relief::view
