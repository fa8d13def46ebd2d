#include "relief/tiles/level_index.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstring>
#include <limits>

#include <fmt/format.h>

#include "relief/tiles/manifest.h"
#include "relief/tiles/tile_file.h"

namespace relief::tiles {
namespace {

constexpr char kMagic[8] = {'R', 'E', 'L', 'I', 'E', 'F', 'I', '\0'};
constexpr uint16_t kVersion = kLevelIndexVersion;
constexpr size_t kFixedHeader = 8 + 2 + 2 + 4 * 4 + 8;
constexpr size_t kRecordSize = kLevelIndexRecordSize;

bool by_row(const IndexEntry& a, const IndexEntry& b) {
  return std::tie(a.key.y, a.key.x) < std::tie(b.key.y, b.key.x);
}

// Writes fields one after the other into a buffer sized up front: every write
// has a known bound (growing a vector field by field made gcc 12 -O3 report
// -Wstringop-overflow writes that cannot happen).
class FieldWriter {
 public:
  explicit FieldWriter(std::span<std::byte> out) : out_(out) {}
  template <class T>
  void put(T v) {
    put_bytes(std::as_bytes(std::span<const T, 1>(&v, 1)));
  }
  void put_bytes(std::span<const std::byte> bytes) {
    const std::span<std::byte> to = out_.subspan(at_, bytes.size());
    std::memcpy(to.data(), bytes.data(), to.size());
    at_ += bytes.size();
  }
  std::span<std::byte> next(size_t n) {
    const std::span<std::byte> to = out_.subspan(at_, n);
    at_ += n;
    return to;
  }
  std::span<const std::byte> written() const { return out_.first(at_); }

 private:
  std::span<std::byte> out_;
  size_t at_ = 0;
};
template <class T>
T read_at(std::span<const std::byte> b, size_t at) {
  T v;
  std::memcpy(&v, b.data() + at, sizeof v);
  return v;
}

}  // namespace

void LevelIndex::add(const IndexEntry& e) {
  assert(e.key.level == level_);
  entries_.push_back(e);
  sorted_ = false;
}

void LevelIndex::set_error(const geo::TileKey& key, float error) {
  const IndexEntry* e = find(key);
  assert(e);
  entries_[static_cast<size_t>(e - entries_.data())].error = error;
}

void LevelIndex::sort() const {
  if (!sorted_) {
    std::sort(entries_.begin(), entries_.end(), by_row);
    sorted_ = true;
  }
}

const std::vector<IndexEntry>& LevelIndex::entries() const {
  sort();
  return entries_;
}

const IndexEntry* LevelIndex::find(const geo::TileKey& key) const {
  sort();
  IndexEntry probe{key};
  auto it = std::lower_bound(entries_.begin(), entries_.end(), probe, by_row);
  if (it == entries_.end() || it->key != key) return nullptr;
  return &*it;
}

uint64_t LevelIndex::total_bytes() const {
  uint64_t sum = 0;
  for (const auto& e : entries_) sum += e.file_bytes;
  return sum;
}

std::vector<std::byte> LevelIndex::serialize() const {
  sort();
  uint32_t x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  if (!entries_.empty()) {
    x0 = y0 = std::numeric_limits<uint32_t>::max();
    for (const auto& e : entries_) {
      x0 = std::min(x0, e.key.x);
      y0 = std::min(y0, e.key.y);
      x1 = std::max(x1, e.key.x + 1);
      y1 = std::max(y1, e.key.y + 1);
    }
  }
  const uint32_t cols = x1 - x0, rows = y1 - y0;
  const uint64_t bitmap_bytes = (static_cast<uint64_t>(cols) * rows + 7) / 8;
  std::vector<std::byte> out(kFixedHeader + bitmap_bytes + entries_.size() * kRecordSize + 4);
  FieldWriter w(out);
  w.put_bytes(std::as_bytes(std::span(kMagic)));
  w.put<uint16_t>(kVersion);
  w.put<uint16_t>(static_cast<uint16_t>(level_));
  w.put<uint32_t>(x0);
  w.put<uint32_t>(y0);
  w.put<uint32_t>(cols);
  w.put<uint32_t>(rows);
  w.put<uint64_t>(entries_.size());
  const std::span<std::byte> bitmap = w.next(bitmap_bytes);  // zeroed by the vector
  for (const auto& e : entries_) {
    const uint64_t bit = static_cast<uint64_t>(e.key.y - y0) * cols + (e.key.x - x0);
    bitmap[bit / 8] |= static_cast<std::byte>(1u << (bit % 8));
  }
  // Entries sorted by (y, x) are exactly bitmap order.
  for (const auto& e : entries_) {
    w.put<float>(std::nextafter(e.min, -std::numeric_limits<float>::infinity()));
    w.put<float>(std::nextafter(e.max, std::numeric_limits<float>::infinity()));
    w.put<uint32_t>(e.valid_count);
    w.put<uint32_t>(e.file_bytes);
    w.put<float>(e.error);
  }
  w.put<uint32_t>(crc32_of(w.written()));
  assert(w.written().size() == out.size());
  return out;
}

Result<LevelIndex> LevelIndex::parse(std::span<const std::byte> b, const std::string& name) {
  return parse_any(b, name, false);
}

Result<LevelIndex> LevelIndex::parse_for_upgrade(std::span<const std::byte> b,
                                                 const std::string& name) {
  return parse_any(b, name, true);
}

Result<LevelIndex> LevelIndex::parse_any(std::span<const std::byte> b, const std::string& name,
                                         bool accept_version1) {
  if (b.size() < kFixedHeader + 4 || std::memcmp(b.data(), kMagic, 8) != 0) {
    return fail(fmt::format("{}: not a relief level index", name));
  }
  if (read_at<uint32_t>(b, b.size() - 4) != crc32_of(b.first(b.size() - 4))) {
    return fail(fmt::format("{}: level index checksum mismatch", name));
  }
  const auto version = read_at<uint16_t>(b, 8);
  if (version != kVersion && version != 1) {
    return fail(fmt::format("{}: unsupported level index version {}", name, version));
  }
  // Version 1 records have no error (it reads as 0).
  const size_t record_size = version == 1 ? 16 : kRecordSize;
  const int level = read_at<uint16_t>(b, 10);
  const auto x0 = read_at<uint32_t>(b, 12), y0 = read_at<uint32_t>(b, 16);
  const auto cols = read_at<uint32_t>(b, 20), rows = read_at<uint32_t>(b, 24);
  const auto count = read_at<uint64_t>(b, 28);
  const uint64_t bitmap_bytes = (static_cast<uint64_t>(cols) * rows + 7) / 8;
  // Each part is bounded by the room it has before they are added: a forged
  // count could otherwise wrap the sum around to the file's size, and the
  // bitmap loop below would read far past the end.
  const uint64_t room = b.size() - kFixedHeader - 4;
  if (level > geo::kMaxLevel || bitmap_bytes > room ||
      count > (room - bitmap_bytes) / record_size || bitmap_bytes + count * record_size != room) {
    return fail(fmt::format("{}: level index is truncated or inconsistent", name));
  }
  LevelIndex index(level);
  size_t record = kFixedHeader + bitmap_bytes;
  for (uint64_t bit = 0; bit < static_cast<uint64_t>(cols) * rows; ++bit) {
    if (!(static_cast<unsigned>(b[kFixedHeader + bit / 8]) & (1u << (bit % 8)))) continue;
    if (record + record_size > b.size() - 4) {
      return fail(fmt::format("{}: level index bitmap and records disagree", name));
    }
    IndexEntry e;
    e.key = {level, x0 + static_cast<uint32_t>(bit % cols), y0 + static_cast<uint32_t>(bit / cols)};
    if (!e.key.valid())
      return fail(fmt::format("{}: level index names a tile outside the level", name));
    e.min = read_at<float>(b, record);
    e.max = read_at<float>(b, record + 4);
    e.valid_count = read_at<uint32_t>(b, record + 8);
    e.file_bytes = read_at<uint32_t>(b, record + 12);
    if (version != 1) e.error = read_at<float>(b, record + 16);
    if (!(e.error >= 0)) {
      return fail(
          fmt::format("{}: tile {} has a geometric error of {}", name, e.key.to_string(), e.error));
    }
    index.entries_.push_back(e);
    record += record_size;
  }
  if (index.entries_.size() != count) {
    return fail(fmt::format("{}: level index bitmap and records disagree", name));
  }
  // Only an index `relief upgrade` can read sends the user there: a damaged
  // one is an error of its own.
  if (version == 1 && !accept_version1) return fail(predates_geometric_errors(name));
  return index;
}

}  // namespace relief::tiles
