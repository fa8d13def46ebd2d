#pragma once
// Typed views over raster memory: extent, row stride, and where the first
// sample sits in the global sample grid of its pyramid level. Nodata is NaN.
//
// Operators take an input view that extends `radius` samples beyond the output
// on every side (a tile with its overlap border, or an image window with a
// margin) and compute every output sample from a neighbourhood that depends
// only on the input values and global positions, never on the view's extent.
// That is what makes a quad processed with its border equal, bit for bit, to
// the same samples of the whole image processed at once.
#include <cassert>
#include <cstddef>
#include <cstdint>

namespace relief::process {

template <class T>
struct View {
  T* data = nullptr;
  int width = 0, height = 0;
  ptrdiff_t stride = 0;                // elements between rows
  int64_t origin_x = 0, origin_y = 0;  // global sample coordinates of (0, 0)

  T& at(int x, int y) const {
    assert(x >= 0 && x < width && y >= 0 && y < height);
    return data[static_cast<ptrdiff_t>(y) * stride + x];
  }
  T* row(int y) const { return data + static_cast<ptrdiff_t>(y) * stride; }
  // The sub-view [x, x+w) x [y, y+h).
  View<T> window(int x, int y, int w, int h) const {
    assert(x >= 0 && y >= 0 && x + w <= width && y + h <= height);
    return {
        data + static_cast<ptrdiff_t>(y) * stride + x, w, h, stride, origin_x + x, origin_y + y};
  }
  operator View<const T>() const { return {data, width, height, stride, origin_x, origin_y}; }
};

using ConstView = View<const float>;
using MutView = View<float>;

}  // namespace relief::process
