#pragma once
// What `relief serve` answers to one request: the response head, then
// (optionally) a byte range of an open store file. Building an answer never
// blocks on a client; sending it is the event loop's job.
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>

#include "http_request.h"
#include "relief/serve/store_server.h"

namespace relief::serve {

struct Answer {
  std::string head;  // status line and header fields, through the empty line
  int file = -1;     // owned by the answer's sender, who closes it; -1: no body from a file
  uint64_t offset = 0, length = 0;  // the file's bytes that follow the head
  bool close = false;               // end the connection once sent
};

// A plain-text status answer (4xx/5xx), its body left out for HEAD.
Answer status_answer(int code, bool keep_alive, bool head_only = false,
                     std::string_view extra_fields = {});

// The answer to a parsed request against the store at `root`: 405 for
// methods other than GET and HEAD, 404 for anything that is not a regular
// store file (or not in the share), 304 on a matching If-None-Match, 206/416 for a single byte
// range, 200 otherwise.
// Only the files of share `share_index` of `share_count` are served (see
// ServeOptions).
// Paths that are no store file go to `generate` when set: its answer is sent
// with an ETag of its body (304 on a match), without ranges, and open to
// pages of any origin (Access-Control-Allow-Origin: *).
Answer answer_request(const std::filesystem::path& root, const Request& request,
                      uint32_t share_index = 0, uint32_t share_count = 1,
                      const Generator& generate = {});

}  // namespace relief::serve
