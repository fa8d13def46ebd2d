#pragma once
// Plain files served by URL path: the pages under /view/ and the libraries
// they load from /lib/ (docs/web.md, "Pages"). Paths are parsed strictly and
// walked one folder at a time without following links, so a request reaches
// only regular files below a mount's folder, whatever the folder holds.
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "relief/web/web_answer.h"

namespace relief::web {

// The files of `dir` answered under the URL prefix `prefix` ("/view/"); the
// prefix itself, and the prefix without its last '/', answer `index` when it
// is set. `dir` itself may be a link (it is configuration, not a request).
struct StaticMount {
  std::string prefix;
  std::filesystem::path dir;
  std::string index;
};

// The mounts of a relief web root: /view/ (view/, index.html),
// /lib/cesium/ (node_modules/cesium/Build/Cesium) and /lib/maplibre/
// (node_modules/maplibre-gl/dist), as `npm ci --prefix web` lays them out.
std::vector<StaticMount> web_root_mounts(const std::filesystem::path& root);

// The segments of a path below a mount, or nullopt for anything but
// '/'-separated names of [A-Za-z0-9._-] that do not start with '.': no
// traversal, no hidden file, no percent-encoding, no backslash, no empty
// segment, at most 16 segments of at most 255 bytes.
std::optional<std::vector<std::string_view>> parse_static_path(std::string_view path);

// The Content-Type for a file name's extension, nullopt for a type not
// served (such a file gets 404).
std::optional<std::string_view> content_type_for(std::string_view file_name);

class StaticFiles {
 public:
  explicit StaticFiles(std::vector<StaticMount> mounts,
                       uint64_t max_file_bytes = uint64_t{64} << 20);
  // The answer for a request path (query cut off), nullopt when it names no
  // servable file. Reads the file on each request; thread-safe.
  std::optional<WebAnswer> answer(std::string_view path) const;

 private:
  std::vector<StaticMount> mounts_;
  uint64_t max_file_bytes_;
};

}  // namespace relief::web
