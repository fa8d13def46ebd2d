#include "relief/parallel/composite.h"

#include <algorithm>
#include <cassert>
#include <charconv>
#include <cstring>
#include <tuple>

#include <fmt/format.h>

namespace relief::parallel {

namespace {

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
  if (count) std::memcpy(runs.data(), message.data() + 4, static_cast<size_t>(count) * 4);
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

Result<Compositing> parse_compositing(std::string_view text) {
  Compositing how;
  if (text == "binary-swap") {
    how.method = Compositing::Method::binary_swap, how.k = 2;
  } else if (text == "direct-send") {
    how.method = Compositing::Method::direct_send, how.k = 0;
  } else if (text == "radix-k") {
    how.method = Compositing::Method::radix_k;
  } else if (text.starts_with("radix-k:")) {
    const std::string_view k = text.substr(8);
    int value = 0;
    const auto [end, error] = std::from_chars(k.data(), k.data() + k.size(), value);
    if (error != std::errc() || end != k.data() + k.size() || value < 2 || value > 1024) {
      return fail(fmt::format("--composite: '{}': K must be a whole number in 2..1024", text));
    }
    how.method = Compositing::Method::radix_k, how.k = value;
  } else {
    return fail(fmt::format(
        "--composite: '{}' is not radix-k, radix-k:K, binary-swap or direct-send", text));
  }
  return how;
}

std::string to_string(const Compositing& how) {
  switch (how.method) {
    case Compositing::Method::binary_swap:
      return "binary-swap";
    case Compositing::Method::direct_send:
      return "direct-send";
    case Compositing::Method::radix_k:
      break;
  }
  return fmt::format("radix-k:{}", how.k);
}

std::vector<int> composite_rounds(const Compositing& how, int ranks) {
  assert(ranks >= 1);
  if (ranks == 1) return {};
  if (how.method == Compositing::Method::direct_send) return {ranks};
  const int k = how.method == Compositing::Method::binary_swap ? 2 : how.k;
  std::vector<int> rounds;
  for (int left = ranks; left > 1;) {
    int factor = 0;
    for (int f = std::min(k, left); f >= 2 && !factor; --f) {
      if (left % f == 0) factor = f;
    }
    // No factor up to k: the smallest prime factor (all exceed k).
    for (int f = k + 1; !factor; ++f) {
      if (left % f == 0) factor = f;
    }
    rounds.push_back(factor);
    left /= factor;
  }
  return rounds;
}

std::pair<int, int> RadixRound::piece(int member) const {
  const int k = static_cast<int>(group.size());
  return {lo + (hi - lo) * member / k, lo + (hi - lo) * (member + 1) / k};
}

// Ranks are numbers in the mixed radix of the rounds, the first round's
// digit lowest: round i groups the ranks that differ only in digit i. Before
// it, a rank holds the composite of the ranks that share its digits from i
// on, a block of consecutive ranks, so the group's members hold consecutive
// blocks in the order of that digit and the lowest rank still wins ties.
std::vector<RadixRound> radix_schedule(int rank, std::span<const int> rounds, int height) {
  std::vector<RadixRound> schedule;
  int stride = 1, lo = 0, hi = height;
  for (const int k : rounds) {
    RadixRound round;
    const int digit = rank / stride % k, base = rank - digit * stride;
    for (int m = 0; m < k; ++m) round.group.push_back(base + m * stride);
    round.position = digit;
    round.lo = lo, round.hi = hi;
    std::tie(lo, hi) = round.piece(digit);
    schedule.push_back(std::move(round));
    stride *= k;
  }
  return schedule;
}

std::pair<int, int> final_rows(int rank, std::span<const int> rounds, int height) {
  const std::vector<RadixRound> schedule = radix_schedule(rank, rounds, height);
  if (schedule.empty()) return {0, height};
  return schedule.back().piece(schedule.back().position);
}

std::vector<std::vector<std::byte>> round_messages(const Layer& held, const RadixRound& round) {
  std::vector<std::vector<std::byte>> out(round.group.size());
  for (int m = 0; m < static_cast<int>(round.group.size()); ++m) {
    if (m == round.position) continue;
    const auto [r0, r1] = round.piece(m);
    out[static_cast<size_t>(m)] = encode_rows(held, r0, r1);
  }
  return out;
}

Status merge_round(Layer& held, const RadixRound& round,
                   std::span<const std::vector<std::byte>> in) {
  assert(in.size() == round.group.size());
  const auto [r0, r1] = round.piece(round.position);
  const int me = round.position, k = static_cast<int>(round.group.size());
  // Ours first, then the higher blocks (which win only when nearer), then
  // the lower ones from the nearest block down (each wins ties over
  // everything merged so far): the nearest, the lowest block's on a tie.
  for (int m = me + 1; m < k; ++m) {
    RELIEF_CHECK(merge_encoded(held, r0, r1, in[static_cast<size_t>(m)], false));
  }
  for (int m = me - 1; m >= 0; --m) {
    RELIEF_CHECK(merge_encoded(held, r0, r1, in[static_cast<size_t>(m)], true));
  }
  return {};
}

Result<std::vector<uint8_t>> depth_composite(Comm& comm, const Layer& layer,
                                             const Compositing& how) {
  const int n = comm.size(), w = layer.width, h = layer.height;
  const std::vector<int> rounds = composite_rounds(how, n);
  Layer held = layer;  // all rows at first; only the rows of the current round matter
  for (const RadixRound& round : radix_schedule(comm.rank(), rounds, h)) {
    std::vector<std::vector<std::byte>> out = round_messages(held, round);
    std::vector<int> others;
    std::vector<std::vector<std::byte>> sent;
    for (size_t m = 0; m < round.group.size(); ++m) {
      if (static_cast<int>(m) == round.position) continue;
      others.push_back(round.group[m]);
      sent.push_back(std::move(out[m]));
    }
    auto received = RELIEF_TRY(exchange_sized(comm, others, sent, others));
    std::vector<std::vector<std::byte>> in(round.group.size());
    for (size_t m = 0, i = 0; m < round.group.size(); ++m) {
      if (static_cast<int>(m) != round.position) in[m] = std::move(received[i++]);
    }
    RELIEF_CHECK(merge_round(held, round, in));
  }
  // Rank 0 gathers the rows' colour.
  std::vector<lod::PixelRect> bands;
  for (int k = 0; k < n; ++k) {
    const auto [k0, k1] = final_rows(k, rounds, h);
    bands.push_back({0, k0, w, k1 - k0});
  }
  const auto [lo, hi] = final_rows(comm.rank(), rounds, h);
  const size_t first = static_cast<size_t>(lo) * static_cast<size_t>(w) * 4;
  return gather_tiles(
      comm,
      std::span<const uint8_t>(held.rgba.data() + first,
                               static_cast<size_t>(hi - lo) * static_cast<size_t>(w) * 4),
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
