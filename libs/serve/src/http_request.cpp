#include "http_request.h"

#include <cctype>
#include <charconv>
#include <string>

namespace relief::serve {
namespace {

// RFC 9110 5.6.2 token characters.
bool is_tchar(char c) {
  if ((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9')) return true;
  return std::string_view("!#$%&'*+-.^_`|~").find(c) != std::string_view::npos;
}

bool is_token(std::string_view s) {
  if (s.empty()) return false;
  for (char c : s) {
    if (!is_tchar(c)) return false;
  }
  return true;
}

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
  return s;
}

bool iequals(std::string_view a, std::string_view b) {
  if (a.size() != b.size()) return false;
  for (size_t i = 0; i < a.size(); ++i) {
    const auto x = static_cast<unsigned char>(a[i]), y = static_cast<unsigned char>(b[i]);
    if (std::tolower(x) != std::tolower(y)) return false;
  }
  return true;
}

// Calls f on every trimmed, non-empty element of a comma-separated list.
template <class F>
void for_each_element(std::string_view list, F&& f) {
  while (!list.empty()) {
    const size_t comma = list.find(',');
    const std::string_view element = trim(list.substr(0, comma));
    if (!element.empty()) f(element);
    if (comma == std::string_view::npos) break;
    list.remove_prefix(comma + 1);
  }
}

void append_field(std::optional<std::string>& field, std::string_view value) {
  // Repeated fields are one comma-separated list (RFC 9110 5.3).
  if (field) {
    *field += ", ";
    *field += value;
  } else {
    field = std::string(value);
  }
}

Status parse_request_line(std::string_view line, Request& r) {
  const size_t a = line.find(' ');
  const size_t b = line.rfind(' ');
  if (a == std::string_view::npos || a == b) return fail("malformed request line");
  const std::string_view method = line.substr(0, a);
  const std::string_view target = line.substr(a + 1, b - a - 1);
  const std::string_view version = line.substr(b + 1);
  if (!is_token(method)) return fail("malformed method");
  if (target.empty()) return fail("empty request target");
  for (char c : target) {
    if (static_cast<unsigned char>(c) <= 0x20 || c == 0x7f) return fail("malformed request target");
  }
  if (version != "HTTP/1.1" && version != "HTTP/1.0") return fail("unsupported HTTP version");
  r.method = method;
  r.target = target;
  r.version = version;
  r.keep_alive = version == "HTTP/1.1";
  return {};
}

Status parse_field(std::string_view line, Request& r, bool& close, bool& keep_alive_token) {
  if (line.empty()) return fail("empty header field line");
  if (line.front() == ' ' || line.front() == '\t') return fail("obsolete line folding");
  const size_t colon = line.find(':');
  if (colon == std::string_view::npos) return fail("header field without a colon");
  const std::string_view name = line.substr(0, colon);
  if (!is_token(name)) return fail("malformed header field name");
  const std::string_view value = trim(line.substr(colon + 1));
  for (char c : value) {
    if (c == '\0' || c == '\r' || c == '\n') return fail("control character in a header field");
  }
  if (iequals(name, "connection")) {
    for_each_element(value, [&](std::string_view token) {
      if (iequals(token, "close")) close = true;
      if (iequals(token, "keep-alive")) keep_alive_token = true;
    });
  } else if (iequals(name, "if-none-match")) {
    append_field(r.if_none_match, value);
  } else if (iequals(name, "range")) {
    append_field(r.range, value);
  } else if (iequals(name, "if-range")) {
    append_field(r.if_range, value);
  } else if (iequals(name, "content-length")) {
    if (value != "0") r.has_body = true;
  } else if (iequals(name, "transfer-encoding")) {
    r.has_body = true;
  }
  return {};
}

std::optional<uint64_t> parse_number(std::string_view s) {
  uint64_t v = 0;
  if (s.empty()) return std::nullopt;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (ec != std::errc() || end != s.data() + s.size()) return std::nullopt;
  return v;
}

std::string_view opaque_tag(std::string_view tag) {
  if (tag.starts_with("W/")) tag.remove_prefix(2);
  return tag;
}

}  // namespace

Result<Request> parse_request_head(std::string_view head) {
  if (head.size() > kMaxRequestHeadBytes) return fail("request head too large");
  const size_t end = head.find("\r\n\r\n");
  if (end == std::string_view::npos) return fail("request head does not end with an empty line");
  if (end + 4 != head.size()) return fail("bytes after the request head");
  Request r;
  size_t line_end = head.find("\r\n");
  RELIEF_CHECK(parse_request_line(head.substr(0, line_end), r));
  bool close = false, keep_alive_token = false;
  // Every field line ends in CRLF, the last one included: walk up to the
  // empty line, not up to the last line break.
  for (size_t pos = line_end + 2; pos < end + 2; pos = line_end + 2) {
    line_end = head.find("\r\n", pos);
    RELIEF_CHECK(parse_field(head.substr(pos, line_end - pos), r, close, keep_alive_token));
  }
  if (close) {
    r.keep_alive = false;
  } else if (keep_alive_token) {
    r.keep_alive = true;
  }
  return r;
}

RangeAnswer resolve_range(std::string_view value, uint64_t size) {
  value = trim(value);
  if (!value.starts_with("bytes=")) return {};
  value.remove_prefix(6);
  value = trim(value);
  if (value.find(',') != std::string_view::npos) return {};  // several ranges: send it all
  const size_t dash = value.find('-');
  if (dash == std::string_view::npos) return {};
  const std::string_view first_text = trim(value.substr(0, dash));
  const std::string_view last_text = trim(value.substr(dash + 1));
  if (first_text.empty()) {  // suffix: the last n bytes
    const auto n = parse_number(last_text);
    if (!n) return {};
    if (*n == 0 || size == 0) return {RangeKind::unsatisfiable, {}};
    return {RangeKind::partial, {size - std::min(*n, size), size - 1}};
  }
  const auto first = parse_number(first_text);
  if (!first) return {};
  uint64_t last = UINT64_MAX;
  if (!last_text.empty()) {
    const auto l = parse_number(last_text);
    if (!l || *l < *first) return {};
    last = *l;
  }
  if (*first >= size) return {RangeKind::unsatisfiable, {}};
  return {RangeKind::partial, {*first, std::min(last, size - 1)}};
}

bool if_none_match_matches(std::string_view value, std::string_view etag) {
  if (trim(value) == "*") return true;
  bool match = false;
  for_each_element(value, [&](std::string_view tag) {
    if (opaque_tag(tag) == opaque_tag(etag)) match = true;
  });
  return match;
}

}  // namespace relief::serve
