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

// Colour then depth of rows [r0, r1) of a layer, as one message.
std::vector<std::byte> pack(const Layer& l, int r0, int r1) {
  const size_t pixels = static_cast<size_t>(r1 - r0) * static_cast<size_t>(l.width);
  const size_t first = static_cast<size_t>(r0) * static_cast<size_t>(l.width);
  std::vector<std::byte> out(pixels * 8);
  std::memcpy(out.data(), l.rgba.data() + first * 4, pixels * 4);
  std::memcpy(out.data() + pixels * 4, l.depth.data() + first, pixels * 4);
  return out;
}

Layer unpack(std::span<const std::byte> bytes, int width, int rows) {
  const size_t pixels = static_cast<size_t>(rows) * static_cast<size_t>(width);
  Layer l{width, rows, std::vector<uint8_t>(pixels * 4), std::vector<float>(pixels)};
  std::memcpy(l.rgba.data(), bytes.data(), pixels * 4);
  std::memcpy(l.depth.data(), bytes.data() + pixels * 4, pixels * 4);
  return l;
}

}  // namespace

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
    const std::vector<std::byte> out = pack(held, give0, give1);
    std::vector<std::byte> in(static_cast<size_t>(keep1 - keep0) * static_cast<size_t>(w) * 8);
    const Comm::Send send{partner, out};
    const Comm::Receive receive{partner, in};
    RELIEF_CHECK(comm.exchange(std::span(&send, 1), std::span(&receive, 1)));
    const Layer theirs = unpack(in, w, keep1 - keep0);
    Layer mine = unpack(pack(held, keep0, keep1), w, keep1 - keep0);
    Layer merged = upper ? theirs : mine;  // the lower block's pixels win ties
    keep_nearer(merged, upper ? mine : theirs);
    // Back into `held` at the kept rows.
    const size_t first = static_cast<size_t>(keep0) * static_cast<size_t>(w);
    std::memcpy(held.rgba.data() + first * 4, merged.rgba.data(), merged.rgba.size());
    std::memcpy(held.depth.data() + first, merged.depth.data(), merged.depth.size() * 4);
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
  std::vector<std::vector<std::byte>> out(static_cast<size_t>(n)), in(static_cast<size_t>(n));
  std::vector<Comm::Send> sends;
  std::vector<Comm::Receive> receives;
  const auto [r0, r1] = band_rows(me, n, h);
  for (int k = 0; k < n; ++k) {
    if (k == me) continue;
    const auto [k0, k1] = band_rows(k, n, h);
    out[static_cast<size_t>(k)] = pack(layer, k0, k1);
    sends.push_back({k, out[static_cast<size_t>(k)]});
    in[static_cast<size_t>(k)].resize(static_cast<size_t>(r1 - r0) * static_cast<size_t>(w) * 8);
    receives.push_back({k, in[static_cast<size_t>(k)]});
  }
  RELIEF_CHECK(comm.exchange(sends, receives));
  // Our band, composited in rank order (lower ranks win ties).
  const std::vector<std::byte> own = pack(layer, r0, r1);
  Layer band = unpack(me == 0 ? std::span<const std::byte>(own) : in[0], w, r1 - r0);
  for (int k = 1; k < n; ++k) {
    const std::vector<std::byte>& bytes = k == me ? own : in[static_cast<size_t>(k)];
    keep_nearer(band, unpack(bytes, w, r1 - r0));
  }
  // Rank 0 gathers the bands' colour.
  std::vector<lod::PixelRect> bands;
  for (int k = 0; k < n; ++k) {
    const auto [k0, k1] = band_rows(k, n, h);
    bands.push_back({0, k0, w, k1 - k0});
  }
  return gather_tiles(comm, band.rgba, bands, w, h);
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
