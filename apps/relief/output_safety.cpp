#include "output_safety.h"

#include <sys/stat.h>

#include <algorithm>
#include <filesystem>

#include <fmt/format.h>

#include "relief/base/file_io.h"

namespace relief::cli {

namespace {
namespace fs = std::filesystem;

// A path as the file system sees it.
struct Resolved {
  std::string text;  // as given, for messages
  fs::path path;     // absolute, symlinks resolved as far as the path exists
  bool exists = false;
  bool directory = false;
  bool store = false;  // a directory holding a relief store's manifest.json
  dev_t device = 0;
  ino_t inode = 0;
};

Resolved resolve(const std::string& text) {
  Resolved r{text, {}};
  std::error_code ec;
  r.path = fs::weakly_canonical(fs::absolute(text, ec), ec);
  if (ec) r.path = fs::absolute(text).lexically_normal();
  // "dir/" names the same directory as "dir".
  if (!r.path.has_filename() && r.path.has_parent_path()) r.path = r.path.parent_path();
  struct stat st {};
  if (::stat(text.c_str(), &st) == 0) {
    r.exists = true;
    r.directory = S_ISDIR(st.st_mode);
    r.store = r.directory && fs::exists(fs::path(text) / "manifest.json", ec);
    r.device = st.st_dev;
    r.inode = st.st_ino;
  }
  return r;
}

// Whether `inner` is strictly below `outer` (both resolved).
bool lies_inside(const fs::path& inner, const fs::path& outer) {
  auto [o, i] = std::mismatch(outer.begin(), outer.end(), inner.begin(), inner.end());
  return o == outer.end() && i != inner.end();
}

bool same_file(const Resolved& a, const Resolved& b) {
  if (a.path == b.path) return true;
  return a.exists && b.exists && a.device == b.device && a.inode == b.inode;
}

Status check_against_input(const Output& out, const Resolved& o, const Resolved& in) {
  if (same_file(o, in)) {
    if (o.text == in.text) {
      return fail(
          fmt::format("{}: {} is also an input; choose another output", out.option, o.text));
    }
    return fail(
        fmt::format("{}: {} is the input {}; choose another output", out.option, o.text, in.text));
  }
  // Any other input directory is not a store, and the command refuses it.
  if (in.store && lies_inside(o.path, in.path)) {
    return fail(fmt::format("{}: {} lies inside the input store {}; writing there would break it",
                            out.option, o.text, in.text));
  }
  if (out.kind == OutputKind::Store && lies_inside(in.path, o.path)) {
    return fail(fmt::format("{}: {} contains the input {}; choose another output", out.option,
                            o.text, in.text));
  }
  return {};
}

Status check_kind(const Output& out, const Resolved& o) {
  if (!o.exists) return {};
  if (out.kind == OutputKind::File) {
    auto replaceable = check_replaceable(o.text);
    if (!replaceable) return fail(fmt::format("{}: {}", out.option, replaceable.error().message));
  } else if (out.kind == OutputKind::Directory && !o.directory) {
    return fail(fmt::format("{}: {} exists and is not a directory", out.option, o.text));
  }
  return {};
}

}  // namespace

Status check_outputs_spare_inputs(const std::vector<Output>& outputs,
                                  const std::vector<std::string>& inputs) {
  std::vector<Resolved> resolved_inputs;
  for (const auto& input : inputs) {
    if (input.empty() || input.find("://") != std::string::npos) continue;
    Resolved in = resolve(input);
    if (in.exists) resolved_inputs.push_back(std::move(in));
  }
  std::vector<std::pair<const Output*, Resolved>> seen;
  for (const auto& out : outputs) {
    if (out.path.empty()) return fail(fmt::format("{}: the path is empty", out.option));
    const Resolved o = resolve(out.path);
    for (const auto& in : resolved_inputs) RELIEF_CHECK(check_against_input(out, o, in));
    RELIEF_CHECK(check_kind(out, o));
    for (const auto& [earlier, path] : seen) {
      if (same_file(o, path)) {
        return fail(
            fmt::format("{}: {} is also the output of {}", out.option, o.text, earlier->option));
      }
    }
    seen.emplace_back(&out, o);
  }
  return {};
}

}  // namespace relief::cli
