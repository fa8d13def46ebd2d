#pragma once
// How far the vertices of a quad's sides move when they take a coarser
// neighbour's data, which refinement adds to the error of the diamonds along
// them (refine.h: edge(D)).
#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>
#include <vector>

namespace relief::lod {

// Range maxima over the heights by which the vertices of one side move when
// they take the coarser neighbour's data (a sparse table).
class SideMax {
 public:
  void build(const std::vector<float>& values) {
    table_.assign(1, values);
    for (size_t w = 1; 2 * w <= values.size(); w *= 2) {
      const std::vector<float>& prev = table_.back();
      std::vector<float> next(values.size() - 2 * w + 1);
      for (size_t i = 0; i < next.size(); ++i) next[i] = std::max(prev[i], prev[i + w]);
      table_.push_back(std::move(next));
    }
  }
  bool empty() const { return table_.empty(); }
  const std::vector<float>& values() const {
    static const std::vector<float> none;
    return table_.empty() ? none : table_[0];
  }
  // Largest value in [a, b], clamped to the side.
  float max(int32_t a, int32_t b) const {
    const int32_t last = static_cast<int32_t>(table_[0].size()) - 1;
    a = std::max(a, 0);
    b = std::min(b, last);
    if (a > b) return 0;
    const int level = std::bit_width(static_cast<uint32_t>(b - a + 1)) - 1;
    const auto& row = table_[static_cast<size_t>(level)];
    return std::max(row[static_cast<size_t>(a)], row[static_cast<size_t>(b - (1 << level) + 1)]);
  }

 private:
  std::vector<std::vector<float>> table_;
};

// How far the vertices of a quad's sides move by taking the coarser
// neighbour's data, per side (west, east, north, south; empty where none
// do), and what they were computed from: the same for every frame that
// selects the quad with the same coarser sides and the same data.
struct SideEdges {
  std::array<SideMax, 4> side;
};

}  // namespace relief::lod
