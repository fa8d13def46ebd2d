#include "output_guard.h"

#include <algorithm>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "relief/base/file_io.h"
#include "relief/tiles/manifest.h"
#include "relief/tiles/store_layout.h"
#include "relief/tiles/store_source.h"

namespace relief::ingest {
namespace fs = std::filesystem;
namespace {

// The file an input names, or empty for one that is no file (a GDAL
// connection string). GDAL virtual paths (/vsizip/a.zip/b.tif) point into a
// real file, which is what must be protected.
fs::path input_file(const std::string& input) {
  std::string path = input;
  const bool is_virtual = path.starts_with("/vsi");
  if (is_virtual) {
    const size_t slash = path.find('/', 1);
    if (slash == std::string::npos) return {};
    path = path.substr(slash + 1);
  }
  std::error_code ec;
  fs::path p = fs::absolute(path, ec);
  while (is_virtual && !fs::exists(p, ec) && p.has_relative_path()) p = p.parent_path();
  if (!fs::exists(p, ec)) return {};
  return fs::canonical(p, ec);
}

// True when `inner` is `outer` or lies inside it (by whole path components).
bool within(const fs::path& inner, const fs::path& outer) {
  auto [o, i] = std::mismatch(outer.begin(), outer.end(), inner.begin(), inner.end());
  // A trailing empty component ("dir/") matches anything.
  return o == outer.end() || (std::next(o) == outer.end() && o->empty());
}

// The name a temporary file will take when its write completes.
std::string final_name(const std::string& relative) {
  const size_t marker = relative.rfind(kTempMarker);
  return marker == std::string::npos ? relative : relative.substr(0, marker);
}

bool is_store_file(const std::string& relative) {
  const std::string name = final_name(relative);
  if (name == tiles::kManifestName) return true;
  if (tiles::tile_key_from_relative_path(name)) return true;
  const size_t slash = name.find('/');
  if (slash == std::string::npos) return false;
  const std::string level = name.substr(0, slash);
  return level.find_first_not_of("0123456789") == std::string::npos && level.size() <= 2 &&
         name == tiles::level_index_relative_path(std::stoi(level));
}

// Level directories ("12") and the tile-block directories below them ("3fa").
bool is_store_directory(const std::string& relative) {
  size_t start = 0;
  for (bool first = true;; first = false) {
    const size_t slash = relative.find('/', start);
    const std::string part = relative.substr(start, slash - start);
    const bool ok =
        first ? !part.empty() && part.size() <= 2 &&
                    part.find_first_not_of("0123456789") == std::string::npos
              : part.size() == 3 && part.find_first_not_of("0123456789abcdef") == std::string::npos;
    if (!ok) return false;
    if (slash == std::string::npos) return true;
    start = slash + 1;
  }
}

Status check_identity(const fs::path& dir) {
  std::error_code ec;
  const fs::path manifest = dir / tiles::kManifestName;
  if (fs::exists(manifest, ec)) {
    auto text = read_text_file(manifest, tiles::kMaxManifestBytes);
    if (!text) return fail(text.error().message);
    if (auto m = tiles::Manifest::from_json(*text, manifest.string()); !m) {
      return fail(m.error().message);
    }
    return {};
  }
  // An interrupted build: its state file is the build's fingerprint.
  const fs::path state = dir / kBuildDir / kStateName;
  auto text = read_text_file(state, kMaxStateBytes);
  if (!text) return fail(fmt::format("{}: has no {}", dir.string(), tiles::kManifestName));
  const auto j = nlohmann::json::parse(*text, nullptr, false);
  if (j.is_discarded() || !j.is_object() || !j.contains("inputs") || !j.contains("kind")) {
    return fail(fmt::format("{}: not a relief build's state file", state.string()));
  }
  return {};
}

}  // namespace

Status check_output_apart_from_inputs(const fs::path& output,
                                      const std::vector<std::string>& inputs) {
  std::error_code ec;
  const fs::path out = fs::weakly_canonical(fs::absolute(output, ec), ec);
  for (const auto& input : inputs) {
    const fs::path in = input_file(input);
    if (in.empty()) continue;
    if (within(in, out)) {
      return fail(fmt::format("{}: the output would hold the input {}; choose another output",
                              output.string(), input));
    }
    if (within(out, in)) {
      return fail(fmt::format("{}: the output lies inside the input {}; choose another output",
                              output.string(), input));
    }
  }
  return {};
}

Status check_only_store_files(const fs::path& dir) {
  if (auto st = check_identity(dir); !st) {
    return fail(fmt::format("{}: not provably a relief store, not replacing it ({})", dir.string(),
                            st.error().message));
  }
  std::error_code ec;
  auto it = fs::recursive_directory_iterator(dir, ec);
  for (; !ec && it != fs::recursive_directory_iterator(); it.increment(ec)) {
    const std::string relative = fs::relative(it->path(), dir, ec).generic_string();
    if (relative == kBuildDir && it->is_directory() && !it->is_symlink()) {
      it.disable_recursion_pending();  // the build's own scratch
      continue;
    }
    const bool ok = it->is_symlink()     ? false
                    : it->is_directory() ? is_store_directory(relative)
                                         : it->is_regular_file() && is_store_file(relative);
    if (!ok) {
      return fail(fmt::format("{}: holds {}, which is not part of a relief store; not replacing it",
                              dir.string(), relative));
    }
  }
  if (ec) return fail(fmt::format("{}: cannot list: {}", dir.string(), ec.message()));
  return {};
}

}  // namespace relief::ingest
