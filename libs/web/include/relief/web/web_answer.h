#pragma once
// What the web side answers for one request: a body and how to label it
// (`relief serve` adds the status line, ETag, CORS and cache fields).
#include <string>

namespace relief::web {

struct WebAnswer {
  std::string content_type;
  std::string content_encoding;  // "gzip" for .terrain bodies
  std::string body;
};

}  // namespace relief::web
