#pragma once
#include <cstdint>
#include <string>
#include <string_view>

#include "relief/base/result.h"

namespace relief {

// Parses sizes such as "1GiB", "512M", "4096" (bytes).
Result<uint64_t> parse_byte_size(std::string_view text);
std::string format_bytes(uint64_t bytes);

}  // namespace relief
