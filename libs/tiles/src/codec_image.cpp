// Image codecs for UInt8 RGBA imagery tiles: PNG (lossless), JPEG (lossy RGB
// plus a zstd-compressed alpha plane, since JPEG has no alpha), WebP (lossy
// colour, lossless alpha).
#include <png.h>
#include <turbojpeg.h>
#include <webp/decode.h>
#include <webp/encode.h>
#include <zstd.h>

#include <cstring>
#include <memory>

#include <fmt/format.h>

#include "relief/tiles/codec.h"

namespace relief::tiles::detail {

namespace {
struct PngWriteState {
  std::vector<std::byte>* out;
};
void png_append(png_structp png, png_bytep data, png_size_t length) {
  auto* state = static_cast<PngWriteState*>(png_get_io_ptr(png));
  const auto* p = reinterpret_cast<const std::byte*>(data);
  state->out->insert(state->out->end(), p, p + length);
}
void png_no_flush(png_structp) {}
}  // namespace

// The low-level libpng API, to choose speed over the last few percent of size:
// zlib level 3 and the "up" and "sub" filters (Paeth costs far more than it
// saves on imagery tiles).
Result<std::vector<std::byte>> encode_png(const Raster& r) {
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  if (!png) return fail("png: cannot initialise the encoder");
  png_infop info = png_create_info_struct(png);
  std::vector<std::byte> out;
  PngWriteState state{&out};
  if (!info || setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, info ? &info : nullptr);
    return fail("png: encoding failed");
  }
  png_set_write_fn(png, &state, png_append, png_no_flush);
  png_set_IHDR(png, info, static_cast<png_uint_32>(r.width()), static_cast<png_uint_32>(r.height()),
               8, PNG_COLOR_TYPE_RGBA, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
               PNG_FILTER_TYPE_DEFAULT);
  png_set_compression_level(png, 3);
  png_set_filter(png, PNG_FILTER_TYPE_BASE, PNG_FILTER_SUB | PNG_FILTER_UP);
  png_write_info(png, info);
  const uint8_t* rows = r.u8().data();
  for (int j = 0; j < r.height(); ++j) {
    png_write_row(png, const_cast<png_bytep>(rows + static_cast<size_t>(j) * r.width() * 4));
  }
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  return out;
}

Result<Raster> decode_png(std::span<const std::byte> p, int w, int h) {
  png_image image{};
  image.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_memory(&image, p.data(), p.size())) {
    return fail(fmt::format("png payload is corrupt: {}", image.message));
  }
  if (static_cast<int>(image.width) != w || static_cast<int>(image.height) != h) {
    png_image_free(&image);
    return fail("png payload does not match the tile header");
  }
  image.format = PNG_FORMAT_RGBA;
  Raster r(SampleType::UInt8, 4, w, h);
  if (!png_image_finish_read(&image, nullptr, r.u8().data(), 0, nullptr)) {
    return fail(fmt::format("png payload is corrupt: {}", image.message));
  }
  return r;
}

namespace {
struct TjDeleter {
  void operator()(void* h) const { tjDestroy(h); }
};
using TjHandle = std::unique_ptr<void, TjDeleter>;

void write_u32(std::span<std::byte, 4> out, uint32_t v) {
  for (size_t i = 0; i < 4; ++i) out[i] = static_cast<std::byte>((v >> (8 * i)) & 0xFF);
}
}  // namespace

// Layout: u32 jpeg size, JPEG bytes (RGB), zstd frame of the alpha plane. The
// output is sized once for its worst case and written at explicit offsets
// (growing it by push_back then insert made gcc 12 -O3 see a write past the
// end that cannot happen: -Wstringop-overflow).
Result<std::vector<std::byte>> encode_jpeg(const Raster& r, int quality) {
  TjHandle tj(tjInitCompress());
  if (!tj) return fail("jpeg: cannot initialise the encoder");
  unsigned char* jpeg = nullptr;
  unsigned long jpeg_size = 0;
  const int status = tjCompress2(tj.get(), r.u8().data(), r.width(), 0, r.height(), TJPF_RGBA,
                                 &jpeg, &jpeg_size, TJSAMP_420, quality, TJFLAG_ACCURATEDCT);
  // turbojpeg allocates the output buffer itself, and may have done so before failing.
  const std::unique_ptr<unsigned char, decltype(&tjFree)> owned(jpeg, &tjFree);
  if (status != 0) return fail(fmt::format("jpeg: {}", tjGetErrorStr2(tj.get())));
  std::vector<uint8_t> alpha(r.pixel_count());
  for (size_t i = 0; i < alpha.size(); ++i) alpha[i] = r.u8()[i * 4 + 3];

  constexpr size_t kSizeField = 4;
  std::vector<std::byte> out(kSizeField + jpeg_size + ZSTD_compressBound(alpha.size()));
  const std::span<std::byte> all(out);
  write_u32(all.first<kSizeField>(), static_cast<uint32_t>(jpeg_size));
  const std::span<std::byte> jpeg_part = all.subspan(kSizeField, jpeg_size);
  std::memcpy(jpeg_part.data(), jpeg, jpeg_part.size());
  const std::span<std::byte> alpha_part = all.subspan(kSizeField + jpeg_size);
  const size_t n =
      ZSTD_compress(alpha_part.data(), alpha_part.size(), alpha.data(), alpha.size(), 3);
  if (ZSTD_isError(n)) return fail("jpeg: cannot compress the alpha plane");
  out.resize(kSizeField + jpeg_size + n);
  return out;
}

Result<Raster> decode_jpeg(std::span<const std::byte> p, int w, int h) {
  if (p.size() < 4) return fail("jpeg payload is truncated");
  uint32_t jpeg_size = 0;
  for (int i = 0; i < 4; ++i)
    jpeg_size |= static_cast<uint32_t>(p[static_cast<size_t>(i)]) << (8 * i);
  if (jpeg_size > p.size() - 4) return fail("jpeg payload is truncated");
  TjHandle tj(tjInitDecompress());
  if (!tj) return fail("jpeg: cannot initialise the decoder");
  auto* jpeg = reinterpret_cast<const unsigned char*>(p.data() + 4);
  int jw = 0, jh = 0, subsamp = 0, colorspace = 0;
  if (tjDecompressHeader3(tj.get(), jpeg, jpeg_size, &jw, &jh, &subsamp, &colorspace) != 0 ||
      jw != w || jh != h) {
    return fail("jpeg payload is corrupt or does not match the tile header");
  }
  Raster r(SampleType::UInt8, 4, w, h);
  // A progressive file of thousands of scans decodes slowly whatever its size:
  // stores never hold one (the encoder writes baseline), so it is refused.
  if (tjDecompress2(tj.get(), jpeg, jpeg_size, r.u8().data(), w, 0, h, TJPF_RGBA,
                    TJFLAG_LIMITSCANS) != 0) {
    return fail(fmt::format("jpeg payload is corrupt: {}", tjGetErrorStr2(tj.get())));
  }
  std::vector<uint8_t> alpha(r.pixel_count());
  auto z = p.subspan(4 + jpeg_size);
  const size_t n = ZSTD_decompress(alpha.data(), alpha.size(), z.data(), z.size());
  if (ZSTD_isError(n) || n != alpha.size()) return fail("jpeg payload has a corrupt alpha plane");
  for (size_t i = 0; i < alpha.size(); ++i) r.u8()[i * 4 + 3] = alpha[i];
  return r;
}

Result<std::vector<std::byte>> encode_webp(const Raster& r, int quality) {
  uint8_t* output = nullptr;
  const size_t size = WebPEncodeRGBA(r.u8().data(), r.width(), r.height(), r.width() * 4,
                                     static_cast<float>(quality), &output);
  if (size == 0) return fail("webp: encoding failed");
  std::vector<std::byte> out(reinterpret_cast<std::byte*>(output),
                             reinterpret_cast<std::byte*>(output) + size);
  WebPFree(output);
  return out;
}

Result<Raster> decode_webp(std::span<const std::byte> p, int w, int h) {
  auto* data = reinterpret_cast<const uint8_t*>(p.data());
  int ww = 0, hh = 0;
  if (!WebPGetInfo(data, p.size(), &ww, &hh) || ww != w || hh != h) {
    return fail("webp payload is corrupt or does not match the tile header");
  }
  Raster r(SampleType::UInt8, 4, w, h);
  if (!WebPDecodeRGBAInto(data, p.size(), r.u8().data(), r.byte_size(), w * 4)) {
    return fail("webp payload is corrupt");
  }
  return r;
}

}  // namespace relief::tiles::detail
