// How refinement stores what it keeps per diamond and per grid point:
// diamond slots (MarkGrid::slot, class by class) and edge marks in blocks
// allocated on first write (SlotMarks, by diamond slot).
#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

#include "edge_marks.h"
#include "mark_blocks.h"

namespace relief::lod {
namespace {

// Every diamond of every class has a slot of its own, all slots used.
TEST(MarkGrid, SlotsNumberTheDiamondsOneToOne) {
  for (int k = 2; k <= 9; ++k) {
    const MarkGrid grid(k);
    std::vector<int> used(grid.slots(), 0);
    for (int c = 0; c <= grid.classes(); ++c) {  // the roots too
      grid.for_each_in_class(c, [&](GridPoint p) {
        ASSERT_LT(grid.slot(p), grid.slots()) << k << " " << p.x << "," << p.y;
        ++used[grid.slot(p)];
      });
    }
    EXPECT_EQ(std::count(used.begin(), used.end(), 1), static_cast<long>(used.size())) << k;
  }
}

// Marks read undecided until written, keep what was written per quad and
// slot, and are all undecided again after reset (blocks are reused).
TEST(SlotMarks, MarksPerQuadAndSlotUndecidedAfterReset) {
  const MarkGrid grid(5);
  SlotMarks marks;
  for (int frame = 0; frame < 2; ++frame) {
    marks.reset(grid, 3);
    for (int q = 0; q < 3; ++q) {
      for (uint32_t slot = 0; slot < grid.slots(); ++slot) {
        ASSERT_EQ(marks.get(q, slot), 0) << frame << " " << q << " " << slot;
      }
    }
    uint8_t& first = marks.at(1, 3);
    first = 2;
    for (uint32_t slot = 0; slot < grid.slots(); slot += 7) marks.at(2, slot) = 1;
    EXPECT_EQ(first, 2);  // still valid after more blocks were allocated
    EXPECT_EQ(marks.get(1, 3), 2);
    EXPECT_EQ(marks.get(0, 3), 0);
    EXPECT_EQ(marks.get(2, 3), 0);
    EXPECT_EQ(marks.get(2, 14), 1);
    EXPECT_EQ(marks.get(2, grid.slots() - 1), (grid.slots() - 1) % 7 == 0 ? 1 : 0);
    marks.prefetch(0, grid.slots() - 1);  // harmless on a block not there
  }
}

}  // namespace
}  // namespace relief::lod
