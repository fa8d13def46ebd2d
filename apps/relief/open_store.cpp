#include "open_store.h"

#include "relief/net/http_source.h"

namespace relief::cli {

Result<tiles::Store> open_store(const std::string& location) {
  if (!location.starts_with("http://") && !location.starts_with("https://")) {
    return tiles::Store::open(location);
  }
  auto source = RELIEF_TRY(net::source_for(location));
  return tiles::Store::open(std::move(source));
}

}  // namespace relief::cli
