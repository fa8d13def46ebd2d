#pragma once
// Depth compositing of sort-last frames (seed 001 §4.1) and assembly of
// sort-first tiles, over a Comm. Every rank keeps, for the rows it
// composites, the nearest fragment of each pixel (reversed-Z: the greatest
// depth; on a tie the lowest rank, whose quads come first) and rank 0
// gathers the rows' colour.
//
// One algorithm, radix-k (Peterka et al. 2009), does the exchange: the rank
// count N is factored into rounds k1 x k2 x ... = N; in round i the ranks
// form groups of k_i, each group splits the rows it holds into k_i pieces
// and each member receives its piece from every other member at once. After
// the last round every rank holds its 1/N of the rows, composited over all
// ranks. Binary swap is every round of 2 (log2 N rounds, one message each);
// direct send one round of N (N - 1 messages each); radix-k:K rounds of at
// most K where N factors so. Exchanged rows are compressed: pixels where the
// sender drew nothing (depth 0, the sky) are skipped as runs, so a rank
// sends only what its quads cover (sort-last ranks each cover about 1/N of
// the image); the result is the same to the bit.
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "relief/base/result.h"
#include "relief/lod/camera.h"
#include "relief/parallel/comm.h"

namespace relief::parallel {

// A rank's frame: RGBA8 and depth, top row first.
struct Layer {
  int width = 0, height = 0;
  std::vector<uint8_t> rgba;
  std::vector<float> depth;
};

// Keeps in `into` the pixels of `from` that are nearer (strictly greater
// depth); both the same size.
void keep_nearer(Layer& into, const Layer& from);

// Rows [r0, r1) of a layer with the empty pixels (depth 0) left out:
// run lengths (skip, copy) and the copied pixels' colour and depth.
std::vector<std::byte> encode_rows(const Layer& layer, int r0, int r1);
// Composites encoded rows into `into`'s rows from `r0` on: a pixel of the
// message replaces `into`'s when nearer, or as near with `message_wins_ties`
// (skipped pixels are empty: the same sky colour on every rank). An error
// for a malformed message.
Status merge_encoded(Layer& into, int r0, int r1, std::span<const std::byte> message,
                     bool message_wins_ties);

// How sort-last layers are composited (`--composite`).
struct Compositing {
  enum class Method { radix_k, binary_swap, direct_send } method = Method::radix_k;
  int k = 8;  // radix_k: the largest group wanted (IceT's default)
};

// radix-k, radix-k:K (K in 2..1024), binary-swap or direct-send; a one-line
// error naming --composite otherwise.
Result<Compositing> parse_compositing(std::string_view text);
std::string to_string(const Compositing& how);

// The group size of each round for `ranks` ranks; their product is `ranks`
// (no rounds for one rank). Radix-k:K takes, while ranks remain, the
// largest factor up to K (or, when none divides, the smallest prime factor:
// a prime rank count composites by direct send). Binary swap is radix-k:2
// (3 ranks: one round of 3; 6: 2 then 3), direct send one round of all.
std::vector<int> composite_rounds(const Compositing& how, int ranks);

// One rank's part in one round.
struct RadixRound {
  std::vector<int> group;  // the ranks exchanging, in block order (lowest ranks' block first)
  int position = 0;        // this rank's place in `group`
  int lo = 0, hi = 0;      // the rows the group holds before the round
  // The rows group member `member` holds after the round.
  std::pair<int, int> piece(int member) const;
};
// Rank `rank`'s rounds for `rounds` (composite_rounds) over `height` rows.
std::vector<RadixRound> radix_schedule(int rank, std::span<const int> rounds, int height);
// The rows `rank` holds, composited, after all of `rounds`.
std::pair<int, int> final_rows(int rank, std::span<const int> rounds, int height);

// A round's messages from this rank: for each group member its piece of
// `held`, encoded (empty for this rank itself).
std::vector<std::vector<std::byte>> round_messages(const Layer& held, const RadixRound& round);
// Composites into `held`'s piece the messages from the group (`in[m]` from
// member m; this rank's own is ignored): the nearest fragment, the lowest
// block's on a tie.
Status merge_round(Layer& held, const RadixRound& round,
                   std::span<const std::vector<std::byte>> in);

// The composited image on rank 0 (empty elsewhere). Every rank passes a
// layer of the same size and the same `how`.
Result<std::vector<uint8_t>> depth_composite(Comm& comm, const Layer& layer,
                                             const Compositing& how);

// The assembled width x height image on rank 0 (empty elsewhere): each
// rank's `tile` of it (RGBA8, top row first) as placed by `tiles[rank]`.
Result<std::vector<uint8_t>> gather_tiles(Comm& comm, std::span<const uint8_t> tile,
                                          std::span<const lod::PixelRect> tiles, int width,
                                          int height);

}  // namespace relief::parallel
