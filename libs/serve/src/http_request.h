#pragma once
// The HTTP/1.1 request head as `relief serve` understands it, parsed by pure
// functions (bytes in, value out: no sockets, no state) so that tests and the
// fuzz target can call them directly.
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "relief/base/result.h"

namespace relief::serve {

constexpr size_t kMaxRequestHeadBytes = 8192;

struct Request {
  std::string method, target, version;
  bool keep_alive = true;                    // HTTP/1.1 default, `Connection` tokens override
  bool has_body = false;                     // Content-Length > 0 or Transfer-Encoding: never read,
                                             // so the connection closes after the answer
  std::optional<std::string> if_none_match;  // raw field value
  std::optional<std::string> range;          // raw field value
  std::optional<std::string> if_range;       // raw field value
};

// Parses one complete request head: the request line and header fields, each
// ending in CRLF, then the empty line (so `head` ends with "\r\n\r\n"; the last
// field counts like every other). Errors for anything malformed: no request
// line, a version other than HTTP/1.0 or 1.1, a field without a colon or with
// whitespace before it, bytes after the empty line, a head over
// kMaxRequestHeadBytes.
Result<Request> parse_request_head(std::string_view head);

// A single byte range resolved against a file of `size` bytes (RFC 9110 14.1).
struct ByteRange {
  uint64_t first = 0, last = 0;  // inclusive
};
enum class RangeKind { whole, partial, unsatisfiable };
struct RangeAnswer {
  RangeKind kind = RangeKind::whole;
  ByteRange range;
};
// `value` of a Range field: "bytes=a-b", "bytes=a-" or "bytes=-n". Several
// ranges, other units and syntax errors give `whole` (the field is ignored, as
// RFC 9110 allows); a range starting at or past the end, or "-0", is
// unsatisfiable.
RangeAnswer resolve_range(std::string_view value, uint64_t size);

// Whether an If-None-Match value ("*" or a list of entity tags, weak or
// strong) matches `etag` by the weak comparison RFC 9110 13.1.2 asks for.
bool if_none_match_matches(std::string_view value, std::string_view etag);

}  // namespace relief::serve
