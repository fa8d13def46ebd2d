#pragma once
#include <string>

#include "relief/base/result.h"
#include "relief/tiles/store.h"

namespace relief::cli {

// A store directory, or a store served over HTTP: "http://host:port/path/",
// several comma-separated URLs for mirrors.
Result<tiles::Store> open_store(const std::string& location);

}  // namespace relief::cli
