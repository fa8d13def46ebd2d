#pragma once
// A display wall (seed 003 §1.4.5): rows x columns of equal displays, one
// rank each, showing one virtual view that includes the pixels hidden behind
// the bezels, so that lines stay straight across displays. The file:
//   {"rows": 2, "columns": 3, "display": [1920, 1080],
//    "bezel": [40, 30],                  // hidden pixels between two displays: x, y
//    "offsets": [[0, 0], [2, -1], ...]}  // optional, per display (row-major), pixels
#include <string>
#include <vector>

#include "relief/base/result.h"
#include "relief/lod/camera.h"

namespace relief::parallel {

struct Wall {
  int rows = 1, columns = 1;
  int display_width = 0, display_height = 0;
  int bezel_x = 0, bezel_y = 0;         // pixels hidden between adjacent displays
  std::vector<lod::PixelRect> offsets;  // x, y of each display's shift (row-major); may be empty
  int displays() const { return rows * columns; }
  int virtual_width() const { return columns * display_width + (columns - 1) * bezel_x; }
  int virtual_height() const { return rows * display_height + (rows - 1) * bezel_y; }
  // The pixels of the virtual view display `index` (row-major) shows.
  lod::PixelRect display(int index) const;
};

// The wall in `path`; a one-line error naming the file and the field otherwise
// (a display shifted outside the virtual view is an error).
Result<Wall> read_wall(const std::string& path);
Result<Wall> parse_wall(const std::string& text, const std::string& where);

}  // namespace relief::parallel
