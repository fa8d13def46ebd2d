// LERC for elevation: every decoded sample is within max_error of the original.
// NaN (nodata) samples travel in LERC's validity mask.
#include <Lerc_c_api.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "relief/tiles/codec.h"

namespace relief::tiles::detail {
namespace {
constexpr unsigned kLercFloat = 6;
}

Result<std::vector<std::byte>> encode_lerc(const Raster& r, double max_error) {
  auto values = r.f32();
  std::vector<unsigned char> valid(values.size());
  bool all_valid = true;
  std::vector<float> data(values.begin(), values.end());
  for (size_t i = 0; i < values.size(); ++i) {
    valid[i] = std::isnan(values[i]) ? 0 : 1;
    if (!valid[i]) {
      all_valid = false;
      data[i] = 0.0f;
    }
  }
  // LERC bounds the error of its quantised value; rounding back to float adds up
  // to half an ulp, so tighten the bound by the ulp of the largest magnitude.
  float largest = 0;
  for (float v : data) largest = std::max(largest, std::abs(v));
  const double ulp = std::nextafter(largest, std::numeric_limits<float>::infinity()) - largest;
  if (max_error > 0) max_error = std::max(0.0, max_error - 2 * ulp);
  const unsigned char* mask = all_valid ? nullptr : valid.data();
  const int masks = all_valid ? 0 : 1;
  unsigned size = 0;
  lerc_status st = lerc_computeCompressedSize(data.data(), kLercFloat, 1, r.width(), r.height(), 1,
                                              masks, mask, max_error, &size);
  if (st != 0) return fail(fmt::format("lerc: cannot size the blob (status {})", st));
  std::vector<std::byte> out(size);
  unsigned written = 0;
  st = lerc_encode(data.data(), kLercFloat, 1, r.width(), r.height(), 1, masks, mask, max_error,
                   reinterpret_cast<unsigned char*>(out.data()), size, &written);
  if (st != 0) return fail(fmt::format("lerc: encoding failed (status {})", st));
  out.resize(written);
  return out;
}

Result<Raster> decode_lerc(std::span<const std::byte> p, int w, int h) {
  unsigned info[10] = {};
  double ranges[3] = {};
  const auto* blob = reinterpret_cast<const unsigned char*>(p.data());
  const auto blob_size = static_cast<unsigned>(p.size());
  if (p.size() > std::numeric_limits<unsigned>::max() ||
      lerc_getBlobInfo(blob, blob_size, info, ranges, 10, 3) != 0) {
    return fail("lerc payload is corrupt");
  }
  // info: [version, dataType, nDepth, nCols, nRows, nBands, nValidPixels, blobSize, nMasks, ...]
  if (info[1] != kLercFloat || info[2] != 1 || static_cast<int>(info[3]) != w ||
      static_cast<int>(info[4]) != h || info[5] != 1) {
    return fail("lerc payload does not match the tile header");
  }
  Raster r(SampleType::Float32, 1, w, h);
  std::vector<unsigned char> valid(r.pixel_count(), 1);
  if (lerc_decode(blob, blob_size, 1, valid.data(), 1, w, h, 1, kLercFloat, r.f32().data()) != 0) {
    return fail("lerc payload is corrupt");
  }
  auto values = r.f32();
  for (size_t i = 0; i < values.size(); ++i) {
    if (!valid[i]) values[i] = std::numeric_limits<float>::quiet_NaN();
  }
  return r;
}

}  // namespace relief::tiles::detail
