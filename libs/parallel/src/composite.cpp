#include "relief/parallel/composite.h"

#include <algorithm>
#include <cassert>
#include <cstring>

namespace relief::parallel {

namespace {

// Rows [first, last) of band `band` of `bands` over `height` rows.
std::pair<int, int> band_rows(int band, int bands, int height) {
  return {height * band / bands, height * (band + 1) / bands};
}

// Messages of sizes the receivers do not know: every size first, then the
// bytes. out[i] goes to rank to[i]; the result holds one message per from[i].
Result<std::vector<std::vector<std::byte>>> exchange_sized(
    Comm& comm, std::span<const int> to, std::span<const std::vector<std::byte>> out,
    std::span<const int> from) {
  std::vector<uint64_t> sizes_out, sizes_in(from.size());
  for (const auto& m : out) sizes_out.push_back(m.size());
  std::vector<Comm::Send> sends;
  std::vector<Comm::Receive> receives;
  for (size_t i = 0; i < to.size(); ++i) sends.push_back({to[i], bytes_of(sizes_out[i])});
  for (size_t i = 0; i < from.size(); ++i) receives.push_back({from[i], bytes_of(sizes_in[i])});
  RELIEF_CHECK(comm.exchange(sends, receives));
  std::vector<std::vector<std::byte>> in(from.size());
  sends.clear(), receives.clear();
  for (size_t i = 0; i < to.size(); ++i) sends.push_back({to[i], out[i]});
  for (size_t i = 0; i < from.size(); ++i) {
    in[i].resize(sizes_in[i]);
    receives.push_back({from[i], in[i]});
  }
  RELIEF_CHECK(comm.exchange(sends, receives));
  return in;
}

}  // namespace

std::vector<std::byte> encode_rows(const Layer& l, int r0, int r1) {
  const size_t first = static_cast<size_t>(r0) * static_cast<size_t>(l.width),
               last = static_cast<size_t>(r1) * static_cast<size_t>(l.width);
  std::vector<uint32_t> runs;  // skip, copy, skip, copy, ...
  std::vector<uint8_t> rgba;
  std::vector<float> depth;
  for (size_t i = first; i < last;) {
    const size_t skip_from = i;
    while (i < last && l.depth[i] == 0) ++i;
    const size_t copy_from = i;
    while (i < last && l.depth[i] != 0) ++i;
    runs.push_back(static_cast<uint32_t>(copy_from - skip_from));
    runs.push_back(static_cast<uint32_t>(i - copy_from));
    rgba.insert(rgba.end(), l.rgba.begin() + static_cast<ptrdiff_t>(copy_from * 4),
                l.rgba.begin() + static_cast<ptrdiff_t>(i * 4));
    depth.insert(depth.end(), l.depth.begin() + static_cast<ptrdiff_t>(copy_from),
                 l.depth.begin() + static_cast<ptrdiff_t>(i));
  }
  const uint32_t count = static_cast<uint32_t>(runs.size());
  std::vector<std::byte> out(4 + runs.size() * 4 + rgba.size() + depth.size() * 4);
  std::byte* p = out.data();
  auto put = [&p](const void* data, size_t bytes) {
    if (bytes) std::memcpy(p, data, bytes);
    p += bytes;
  };
  put(&count, 4);
  put(runs.data(), runs.size() * 4);
  put(rgba.data(), rgba.size());
  put(depth.data(), depth.size() * 4);
  return out;
}

Status merge_encoded(Layer& into, int r0, int r1, std::span<const std::byte> message,
                     bool message_wins_ties) {
  uint32_t count = 0;
  if (message.size() < 4) return fail("compositing: a message without its header");
  std::memcpy(&count, message.data(), 4);
  if (count % 2 || (message.size() - 4) / 4 < count) {
    return fail("compositing: a message with a malformed run table");
  }
  std::vector<uint32_t> runs(count);
  std::memcpy(runs.data(), message.data() + 4, static_cast<size_t>(count) * 4);
  size_t pixels = 0, copied = 0;
  for (uint32_t k = 0; k < count; k += 2) pixels += runs[k] + runs[k + 1], copied += runs[k + 1];
  const size_t rows_pixels = static_cast<size_t>(r1 - r0) * static_cast<size_t>(into.width);
  const size_t body = 4 + static_cast<size_t>(count) * 4;
  if (pixels != rows_pixels || message.size() != body + copied * 8) {
    return fail("compositing: a message whose runs do not cover its rows");
  }
  const std::byte* colour = message.data() + body;
  const std::byte* depths = colour + copied * 4;
  size_t at = static_cast<size_t>(r0) * static_cast<size_t>(into.width), c = 0;
  for (uint32_t k = 0; k < count; k += 2) {
    at += runs[k];
    for (uint32_t n = 0; n < runs[k + 1]; ++n, ++at, ++c) {
      float d = 0;
      std::memcpy(&d, depths + c * 4, 4);
      if (d > into.depth[at] || (message_wins_ties && d == into.depth[at])) {
        into.depth[at] = d;
        std::memcpy(&into.rgba[at * 4], colour + c * 4, 4);
      }
    }
  }
  return {};
}

void keep_nearer(Layer& into, const Layer& from) {
  assert(into.depth.size() == from.depth.size());
  for (size_t i = 0; i < into.depth.size(); ++i) {
    if (from.depth[i] > into.depth[i]) {
      into.depth[i] = from.depth[i];
      std::memcpy(&into.rgba[i * 4], &from.rgba[i * 4], 4);
    }
  }
}

namespace {

bool power_of_two(int n) {
  return n > 0 && (n & (n - 1)) == 0;
}

// Binary swap (power-of-two rank counts): in round r, ranks 2^r apart
// split the rows they still hold; each keeps one half, sends the other and
// composites what it receives. After log2 N rounds every rank holds 1/N of
// the rows, composited over all ranks. Ranks pair as blocks of consecutive
// ranks, lower block against higher, so the lowest rank still wins ties.
Result<std::vector<uint8_t>> binary_swap(Comm& comm, const Layer& layer) {
  const int n = comm.size(), me = comm.rank(), w = layer.width, h = layer.height;
  // The rows each rank holds after the last round.
  auto rows_of = [&](int rank) {
    int lo = 0, hi = h;
    for (int bit = 1; bit < n; bit <<= 1) {
      const int mid = (lo + hi) / 2;
      (rank & bit ? lo : hi) = mid;
    }
    return std::pair{lo, hi};
  };
  Layer held = layer;  // all rows at first; only [lo, hi) matter
  int lo = 0, hi = h;
  for (int bit = 1; bit < n; bit <<= 1) {
    const int partner = me ^ bit, mid = (lo + hi) / 2;
    const bool upper = me & bit;
    const auto [keep0, keep1] = upper ? std::pair{mid, hi} : std::pair{lo, mid};
    const auto [give0, give1] = upper ? std::pair{lo, mid} : std::pair{mid, hi};
    const std::vector<std::byte> out = encode_rows(held, give0, give1);
    auto in = RELIEF_TRY(
        exchange_sized(comm, std::span(&partner, 1), std::span(&out, 1), std::span(&partner, 1)));
    // The lower block's pixels win ties.
    RELIEF_CHECK(merge_encoded(held, keep0, keep1, in[0], upper));
    lo = keep0, hi = keep1;
  }
  std::vector<lod::PixelRect> bands;
  for (int k = 0; k < n; ++k) {
    const auto [k0, k1] = rows_of(k);
    bands.push_back({0, k0, w, k1 - k0});
  }
  const size_t first = static_cast<size_t>(lo) * static_cast<size_t>(w) * 4;
  return gather_tiles(
      comm,
      std::span<const uint8_t>(held.rgba.data() + first,
                               static_cast<size_t>(hi - lo) * static_cast<size_t>(w) * 4),
      bands, w, h);
}

}  // namespace

const char* compositing_method(int ranks) {
  return power_of_two(ranks) ? "binary-swap" : "direct-send";
}

Result<std::vector<uint8_t>> depth_composite(Comm& comm, const Layer& layer) {
  if (power_of_two(comm.size())) return binary_swap(comm, layer);
  const int n = comm.size(), me = comm.rank(), w = layer.width, h = layer.height;
  // Send every other rank its band; receive our band from every other rank.
  std::vector<int> others;
  std::vector<std::vector<std::byte>> out;
  for (int k = 0; k < n; ++k) {
    if (k == me) continue;
    const auto [k0, k1] = band_rows(k, n, h);
    others.push_back(k);
    out.push_back(encode_rows(layer, k0, k1));
  }
  const auto in = RELIEF_TRY(exchange_sized(comm, others, out, others));
  // Our band: the nearest fragment, the lowest rank's on a tie. Ours first,
  // then the higher ranks (which win only when nearer), then the lower ones
  // from the nearest rank down (each wins ties over everything merged so far).
  const auto [r0, r1] = band_rows(me, n, h);
  Layer band = layer;  // rows [r0, r1) matter
  for (size_t i = 0; i < others.size(); ++i) {
    if (others[i] > me) RELIEF_CHECK(merge_encoded(band, r0, r1, in[i], false));
  }
  for (size_t i = others.size(); i-- > 0;) {
    if (others[i] < me) RELIEF_CHECK(merge_encoded(band, r0, r1, in[i], true));
  }
  // Rank 0 gathers the bands' colour.
  std::vector<lod::PixelRect> bands;
  for (int k = 0; k < n; ++k) {
    const auto [k0, k1] = band_rows(k, n, h);
    bands.push_back({0, k0, w, k1 - k0});
  }
  const size_t first = static_cast<size_t>(r0) * static_cast<size_t>(w) * 4;
  return gather_tiles(
      comm,
      std::span<const uint8_t>(band.rgba.data() + first,
                               static_cast<size_t>(r1 - r0) * static_cast<size_t>(w) * 4),
      bands, w, h);
}

Result<std::vector<uint8_t>> gather_tiles(Comm& comm, std::span<const uint8_t> tile,
                                          std::span<const lod::PixelRect> tiles, int width,
                                          int height) {
  const int n = comm.size(), me = comm.rank();
  assert(static_cast<int>(tiles.size()) == n);
  if (me != 0) {
    const Comm::Send send{0, std::as_bytes(tile)};
    RELIEF_CHECK(comm.exchange(std::span(&send, 1), {}));
    return std::vector<uint8_t>();
  }
  std::vector<std::vector<uint8_t>> parts(static_cast<size_t>(n));
  std::vector<Comm::Receive> receives;
  for (int k = 1; k < n; ++k) {
    const lod::PixelRect& t = tiles[static_cast<size_t>(k)];
    auto& part = parts[static_cast<size_t>(k)];
    part.resize(static_cast<size_t>(t.width) * static_cast<size_t>(t.height) * 4);
    receives.push_back({k, std::as_writable_bytes(std::span(part))});
  }
  RELIEF_CHECK(comm.exchange({}, receives));
  parts[0].assign(tile.begin(), tile.end());
  std::vector<uint8_t> image(static_cast<size_t>(width) * static_cast<size_t>(height) * 4);
  for (int k = 0; k < n; ++k) {
    const lod::PixelRect& t = tiles[static_cast<size_t>(k)];
    const size_t row = static_cast<size_t>(t.width) * 4;
    for (int y = 0; y < t.height; ++y) {
      std::memcpy(&image[(static_cast<size_t>(t.y + y) * static_cast<size_t>(width) +
                          static_cast<size_t>(t.x)) *
                         4],
                  &parts[static_cast<size_t>(k)][static_cast<size_t>(y) * row], row);
    }
  }
  return image;
}

}  // namespace relief::parallel
