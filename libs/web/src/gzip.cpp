#include <zlib.h>
#include <cassert>

#include "relief/web/quantized_mesh.h"

namespace relief::web {

std::vector<std::byte> gzip(const std::vector<std::byte>& bytes) {
  z_stream z{};
  // windowBits 15 + 16: a gzip wrapper with a zeroed header (no name, time 0).
  [[maybe_unused]] const int init = deflateInit2(&z, 6, Z_DEFLATED, 15 + 16, 8, Z_DEFAULT_STRATEGY);
  assert(init == Z_OK);
  std::vector<std::byte> out(deflateBound(&z, static_cast<uLong>(bytes.size())) + 32);
  z.next_in = reinterpret_cast<Bytef*>(const_cast<std::byte*>(bytes.data()));
  z.avail_in = static_cast<uInt>(bytes.size());
  z.next_out = reinterpret_cast<Bytef*>(out.data());
  z.avail_out = static_cast<uInt>(out.size());
  [[maybe_unused]] const int done = deflate(&z, Z_FINISH);
  assert(done == Z_STREAM_END);
  out.resize(z.total_out);
  deflateEnd(&z);
  return out;
}

}  // namespace relief::web
