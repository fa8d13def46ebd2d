#include "answer.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <fmt/format.h>

#include <optional>

#include "relief/serve/store_server.h"

namespace relief::serve {
namespace {

std::string_view reason(int code) {
  switch (code) {
    case 200:
      return "OK";
    case 206:
      return "Partial Content";
    case 304:
      return "Not Modified";
    case 400:
      return "Bad Request";
    case 404:
      return "Not Found";
    case 405:
      return "Method Not Allowed";
    case 416:
      return "Range Not Satisfiable";
    case 431:
      return "Request Header Fields Too Large";
    case 503:
      return "Service Unavailable";
    default:
      return "Internal Server Error";
  }
}

std::string_view connection(bool keep_alive) {
  return keep_alive ? "keep-alive" : "close";
}

// Opens a store file without ever blocking or leaving the file: no symlink
// as the last component, O_NONBLOCK so a FIFO planted at a tile path cannot
// hold the thread in open(), and only regular files are served.
int open_regular_file(const std::filesystem::path& path, struct stat& st) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) return -1;
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    ::close(fd);
    return -1;
  }
  return fd;
}

// The fields of every 200, 206 and 304 answer; `extra` says what kind of body.
std::string common_fields(const std::string& etag, std::string_view extra, bool keep_alive) {
  return fmt::format(
      "Server: relief\r\nETag: {}\r\nCache-Control: public, max-age=300\r\n{}"
      "Connection: {}\r\n",
      etag, extra, connection(keep_alive));
}

// 304 when the client already holds this version.
std::optional<Answer> not_modified(const Request& r, const std::string& etag,
                                   const std::string& common, bool keep_alive) {
  if (!r.if_none_match || !if_none_match_matches(*r.if_none_match, etag)) return std::nullopt;
  Answer a;
  a.close = !keep_alive;
  a.head = "HTTP/1.1 304 Not Modified\r\n" + common + "\r\n";
  return a;
}

// A generated body's version is its content: a 64-bit hash and the length.
Answer generated_answer(const Request& r, const GeneratedAnswer& g, bool keep_alive,
                        bool head_only) {
  const std::string etag =
      fmt::format("\"g{:016x}-{:x}\"", std::hash<std::string_view>{}(g.body), g.body.size());
  std::string common = common_fields(etag, "Access-Control-Allow-Origin: *\r\n", keep_alive);
  if (auto a = not_modified(r, etag, common, keep_alive)) return std::move(*a);
  Answer a;
  a.close = !keep_alive;
  if (!g.content_encoding.empty())
    common += fmt::format("Content-Encoding: {}\r\n", g.content_encoding);
  a.head = fmt::format("HTTP/1.1 200 OK\r\n{}Content-Type: {}\r\nContent-Length: {}\r\n\r\n",
                       common, g.content_type, g.body.size());
  if (!head_only) a.head += g.body;
  return a;
}

}  // namespace

Answer status_answer(int code, bool keep_alive, bool head_only, std::string_view extra_fields) {
  const std::string body = fmt::format("{} {}\n", code, reason(code));
  Answer a;
  a.close = !keep_alive;
  a.head = fmt::format(
      "HTTP/1.1 {} {}\r\nServer: relief\r\nContent-Type: text/plain\r\n"
      "Content-Length: {}\r\nConnection: {}\r\n{}\r\n",
      code, reason(code), body.size(), connection(keep_alive), extra_fields);
  if (!head_only) a.head += body;
  return a;
}

Answer answer_request(const std::filesystem::path& root, const Request& r, uint32_t share_index,
                      uint32_t share_count, const Generator& generate) {
  const bool head_only = r.method == "HEAD";
  const bool keep_alive = r.keep_alive && !r.has_body;  // a body is never read: end there
  if (r.method != "GET" && !head_only) {
    return status_answer(405, keep_alive, false, "Allow: GET, HEAD\r\n");
  }
  const auto file = store_file_for(r.target);
  if (!file && generate) {
    if (auto g = generate(r.target)) return generated_answer(r, *g, keep_alive, head_only);
  }
  if (!file || !in_share(*file, share_index, share_count)) {
    return status_answer(404, keep_alive, head_only);
  }
  struct stat st {};
  const int fd = open_regular_file(root / *file, st);
  if (fd < 0) return status_answer(404, keep_alive, head_only);
  const auto size = static_cast<uint64_t>(st.st_size);
  // Store files are written once, atomically: size and modification time name a version.
  const std::string etag =
      fmt::format("\"{:x}-{:x}{:09x}\"", size, st.st_mtim.tv_sec, st.st_mtim.tv_nsec);
  const std::string common = common_fields(etag, "Accept-Ranges: bytes\r\n", keep_alive);
  if (auto unchanged = not_modified(r, etag, common, keep_alive)) {
    ::close(fd);
    return std::move(*unchanged);
  }
  Answer a;
  a.close = !keep_alive;
  RangeAnswer range;
  if (r.range && (!r.if_range || *r.if_range == etag)) range = resolve_range(*r.range, size);
  if (range.kind == RangeKind::unsatisfiable) {
    ::close(fd);
    return status_answer(416, keep_alive, head_only,
                         fmt::format("Content-Range: bytes */{}\r\n", size));
  }
  const char* type = file->ends_with(".json") ? "application/json" : "application/octet-stream";
  if (range.kind == RangeKind::partial) {
    a.offset = range.range.first;
    a.length = range.range.last - range.range.first + 1;
    a.head = fmt::format(
        "HTTP/1.1 206 Partial Content\r\n{}Content-Type: {}\r\nContent-Range: bytes {}-{}/{}\r\n"
        "Content-Length: {}\r\n\r\n",
        common, type, range.range.first, range.range.last, size, a.length);
  } else {
    a.length = size;
    a.head = fmt::format("HTTP/1.1 200 OK\r\n{}Content-Type: {}\r\nContent-Length: {}\r\n\r\n",
                         common, type, size);
  }
  if (head_only || a.length == 0) {
    ::close(fd);
    a.length = 0;
  } else {
    a.file = fd;
  }
  return a;
}

}  // namespace relief::serve
