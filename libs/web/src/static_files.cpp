#include "relief/web/static_files.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <utility>

namespace relief::web {
namespace {

constexpr size_t kMaxSegments = 16, kMaxSegmentBytes = 255;

bool name_char(char c) {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '.' ||
         c == '_' || c == '-';
}

// Closes a descriptor when it goes out of scope.
class Fd {
 public:
  explicit Fd(int fd) : fd_(fd) {}
  ~Fd() {
    if (fd_ >= 0) ::close(fd_);
  }
  Fd(const Fd&) = delete;
  Fd& operator=(const Fd&) = delete;
  Fd(Fd&& o) noexcept : fd_(std::exchange(o.fd_, -1)) {}
  Fd& operator=(Fd&& o) noexcept {
    std::swap(fd_, o.fd_);
    return *this;
  }
  int get() const { return fd_; }

 private:
  int fd_;
};

// The body of the regular file `segments` names below `dir`. Each folder is
// opened relative to the previous one with O_NOFOLLOW, so no link anywhere
// below `dir` leads out of it; O_NONBLOCK keeps a FIFO from holding the
// event loop in open().
std::optional<std::string> read_below(const std::filesystem::path& dir,
                                      const std::vector<std::string_view>& segments,
                                      uint64_t max_bytes) {
  Fd at(::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC));
  if (at.get() < 0) return std::nullopt;
  for (size_t i = 0; i < segments.size(); ++i) {
    const std::string name(segments[i]);
    const bool last = i + 1 == segments.size();
    const int flags = O_RDONLY | O_NOFOLLOW | O_CLOEXEC | (last ? O_NONBLOCK : O_DIRECTORY);
    Fd next(::openat(at.get(), name.c_str(), flags));
    if (next.get() < 0) return std::nullopt;
    at = std::move(next);
  }
  struct stat st {};
  if (::fstat(at.get(), &st) != 0 || !S_ISREG(st.st_mode)) return std::nullopt;
  if (static_cast<uint64_t>(st.st_size) > max_bytes) return std::nullopt;
  std::string body(static_cast<size_t>(st.st_size), '\0');
  size_t done = 0;
  while (done < body.size()) {
    const ssize_t n = ::read(at.get(), body.data() + done, body.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return std::nullopt;  // shrank while read, or an error: no half answer
    done += static_cast<size_t>(n);
  }
  return body;
}

}  // namespace

std::vector<StaticMount> web_root_mounts(const std::filesystem::path& root) {
  return {{"/view/", root / "view", "index.html"},
          {"/map/", root / "map", "index.html"},
          {"/lib/cesium/", root / "node_modules/cesium/Build/Cesium", ""},
          {"/lib/maplibre/", root / "node_modules/maplibre-gl/dist", ""}};
}

std::optional<std::vector<std::string_view>> parse_static_path(std::string_view path) {
  std::vector<std::string_view> segments;
  for (;;) {
    const size_t slash = path.find('/');
    const std::string_view segment = path.substr(0, slash);
    if (segment.empty() || segment.size() > kMaxSegmentBytes || segment[0] == '.')
      return std::nullopt;
    for (const char c : segment) {
      if (!name_char(c)) return std::nullopt;
    }
    if (segments.size() == kMaxSegments) return std::nullopt;
    segments.push_back(segment);
    if (slash == std::string_view::npos) return segments;
    path.remove_prefix(slash + 1);
  }
}

std::optional<std::string_view> content_type_for(std::string_view file_name) {
  static constexpr std::array<std::pair<std::string_view, std::string_view>, 17> kTypes{{
      {".html", "text/html; charset=utf-8"},
      {".js", "text/javascript; charset=utf-8"},
      {".mjs", "text/javascript; charset=utf-8"},
      {".cjs", "text/javascript; charset=utf-8"},
      {".css", "text/css; charset=utf-8"},
      {".json", "application/json"},
      {".map", "application/json"},
      {".png", "image/png"},
      {".jpg", "image/jpeg"},
      {".gif", "image/gif"},
      {".svg", "image/svg+xml"},
      {".wasm", "application/wasm"},
      {".xml", "application/xml"},
      {".glb", "model/gltf-binary"},
      {".ktx2", "image/ktx2"},
      {".woff", "font/woff"},
      {".woff2", "font/woff2"},
  }};
  for (const auto& [extension, type] : kTypes) {
    if (file_name.ends_with(extension)) return type;
  }
  return std::nullopt;
}

StaticFiles::StaticFiles(std::vector<StaticMount> mounts, uint64_t max_file_bytes)
    : mounts_(std::move(mounts)), max_file_bytes_(max_file_bytes) {}

std::optional<WebAnswer> StaticFiles::answer(std::string_view path) const {
  for (const StaticMount& m : mounts_) {
    std::string_view rest;
    const std::string_view bare = std::string_view(m.prefix).substr(0, m.prefix.size() - 1);
    if (!m.index.empty() && (path == m.prefix || path == bare)) {
      rest = m.index;
    } else if (path.starts_with(m.prefix)) {
      rest = path.substr(m.prefix.size());
    } else {
      continue;
    }
    const auto segments = parse_static_path(rest);
    if (!segments) return std::nullopt;
    const auto type = content_type_for(segments->back());
    if (!type) return std::nullopt;
    auto body = read_below(m.dir, *segments, max_file_bytes_);
    if (!body) return std::nullopt;
    return WebAnswer{std::string(*type), "", std::move(*body)};
  }
  return std::nullopt;
}

}  // namespace relief::web
