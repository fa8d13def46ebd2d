#include "relief/net/http_source.h"

#include <curl/curl.h>

#include <atomic>
#include <chrono>
#include <mutex>
#include <thread>

#include <fmt/format.h>

#include "relief/base/units.h"
#include "relief/tiles/store_layout.h"

namespace relief::net {
namespace {

struct CurlInit {
  CurlInit() { curl_global_init(CURL_GLOBAL_DEFAULT); }
};

// One attempt's outcome: bytes, or an error and whether trying again may help.
struct Attempt {
  std::vector<std::byte> body;
  uint64_t cap = 0;  // the largest body accepted
  bool too_large = false;
  std::string error;
  bool retry = false;
  bool not_found = false;
};

// Appends to the body; a body growing past the cap (a chunked or lying
// server) aborts the transfer at once (returning less than given).
size_t append(char* data, size_t size, size_t count, void* out) {
  auto* a = static_cast<Attempt*>(out);
  const size_t n = size * count;
  if (a->body.size() + n > a->cap) {
    a->too_large = true;
    return 0;
  }
  const auto* p = reinterpret_cast<const std::byte*>(data);
  a->body.insert(a->body.end(), p, p + n);
  return n;
}

class CurlHttpSource final : public HttpSource {
 public:
  explicit CurlHttpSource(HttpOptions o) : o_(std::move(o)) {
    for (auto& u : o_.base_urls) {
      if (!u.ends_with('/')) u += '/';
    }
  }
  ~CurlHttpSource() override {
    for (CURL* h : handles_) curl_easy_cleanup(h);
  }

  std::string name() const override { return o_.base_urls.front(); }

  HttpStats stats() const override { return {requests_, retries_, failovers_, bytes_, rejected_}; }

  Result<std::vector<std::byte>> fetch(const std::string& relative) const override {
    const size_t n = o_.base_urls.size();
    size_t first = 0;
    bool pinned = false;  // distributed tiles live on one server only
    if (auto key = tiles::tile_key_from_relative_path(relative)) {
      first = static_cast<size_t>(key->morton() % n);
      pinned = o_.layout == ServerLayout::Distributed;
    } else {
      first = std::hash<std::string>()(relative) % n;
    }
    // Tiles are capped by the shape of the store whose manifest came through
    // here (a Store fetches it first).
    const uint64_t cap = caps_.cap(relative);
    std::string last_error;
    for (size_t k = 0; k < (pinned ? 1 : n); ++k) {
      if (k > 0) ++failovers_;
      const std::string& base = o_.base_urls[(first + k) % n];
      long backoff = o_.backoff_ms;
      for (int attempt = 0; attempt < o_.attempts; ++attempt) {
        if (attempt > 0) {
          ++retries_;
          std::this_thread::sleep_for(std::chrono::milliseconds(backoff));
          backoff *= 2;
        }
        Attempt a = get(base + relative, cap);
        if (a.not_found) return fail(fmt::format("{}{}: not found (404)", base, relative));
        if (a.error.empty()) {
          if (auto ok = tiles::StoreSource::verify(relative, a.body); ok) {
            bytes_ += a.body.size();
            caps_.learn(relative, a.body);
            return std::move(a.body);
          } else {
            ++rejected_;
            a.error = ok.error().message;
            a.retry = true;
          }
        }
        last_error = fmt::format("{}{}: {}", base, relative, a.error);
        if (!a.retry) break;
      }
    }
    return fail(last_error);
  }

 private:
  CURL* borrow() const {
    std::lock_guard lock(mutex_);
    if (!handles_.empty()) {
      CURL* h = handles_.back();
      handles_.pop_back();
      return h;
    }
    return curl_easy_init();
  }
  void give_back(CURL* h) const {
    std::lock_guard lock(mutex_);
    handles_.push_back(h);
  }

  Attempt get(const std::string& url, uint64_t cap) const {
    ++requests_;
    CURL* h = borrow();
    Attempt a;
    a.cap = cap;
    curl_easy_reset(h);
    curl_easy_setopt(h, CURLOPT_URL, url.c_str());
    curl_easy_setopt(h, CURLOPT_WRITEFUNCTION, append);
    curl_easy_setopt(h, CURLOPT_WRITEDATA, &a);
    // Refuses a larger Content-Length before the body; append() checks the rest.
    curl_easy_setopt(h, CURLOPT_MAXFILESIZE_LARGE, static_cast<curl_off_t>(cap));
    curl_easy_setopt(h, CURLOPT_CONNECTTIMEOUT_MS, o_.connect_timeout_ms);
    curl_easy_setopt(h, CURLOPT_TIMEOUT_MS, o_.timeout_ms);
    curl_easy_setopt(h, CURLOPT_NOSIGNAL, 1L);
    curl_easy_setopt(h, CURLOPT_FOLLOWLOCATION, 0L);
    const CURLcode rc = curl_easy_perform(h);
    long status = 0;
    curl_easy_getinfo(h, CURLINFO_RESPONSE_CODE, &status);
    give_back(h);
    if (a.too_large || rc == CURLE_FILESIZE_EXCEEDED) {
      // Not retried: the server means it. Mirrors may still have the right file.
      a.error =
          fmt::format("response larger than {}, the most this file can be", format_bytes(cap));
    } else if (rc != CURLE_OK) {
      a.error = curl_easy_strerror(rc);  // refused, timed out, truncated body, ...
      a.retry = true;
    } else if (status == 404) {
      a.not_found = true;
    } else if (status != 200) {
      a.error = fmt::format("HTTP {}", status);
      a.retry = status >= 500;
    }
    return a;
  }

  HttpOptions o_;
  mutable std::mutex mutex_;
  mutable std::vector<CURL*> handles_;
  mutable tiles::FileCaps caps_;
  mutable std::atomic<uint64_t> requests_{0}, retries_{0}, failovers_{0}, bytes_{0}, rejected_{0};
};

}  // namespace

Result<std::shared_ptr<HttpSource>> HttpSource::create(HttpOptions o) {
  static CurlInit init;
  if (o.base_urls.empty()) return fail("HTTP source: no server");
  for (const auto& u : o.base_urls) {
    if (!u.starts_with("http://") && !u.starts_with("https://")) {
      return fail(fmt::format("{}: not an http:// or https:// URL", u));
    }
  }
  if (o.attempts < 1) return fail("HTTP source: attempts must be >= 1");
  return std::shared_ptr<HttpSource>(std::make_shared<CurlHttpSource>(std::move(o)));
}

Result<std::shared_ptr<const tiles::StoreSource>> source_for(const std::string& location) {
  constexpr std::string_view kCyclic = "cyclic:";
  HttpOptions o;
  size_t start = 0;
  if (location.starts_with(kCyclic)) {
    o.layout = ServerLayout::Distributed;
    start = kCyclic.size();
  } else if (!location.starts_with("http://") && !location.starts_with("https://")) {
    return tiles::local_source(location);
  }
  for (;;) {
    const size_t comma = location.find(',', start);
    o.base_urls.push_back(
        location.substr(start, comma == std::string::npos ? comma : comma - start));
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  auto s = RELIEF_TRY(HttpSource::create(std::move(o)));
  return std::shared_ptr<const tiles::StoreSource>(std::move(s));
}

}  // namespace relief::net
