#include "engine/vision/cell_grid.h"

#include <algorithm>

namespace plantscale::vision {

void CellCoordinate(int i, int cell_px, int cells, int& c0, int& c1, int& w256) {
  const double c = (i + 0.5) / cell_px - 0.5;
  const double clamped = std::clamp(c, 0.0, static_cast<double>(cells - 1));
  c0 = static_cast<int>(clamped);
  c1 = std::min(c0 + 1, cells - 1);
  w256 = static_cast<int>((clamped - c0) * 256.0 + 0.5);
}

namespace {

// One cell row interpolated along u when the row is a whole number of
// cells of even size K: the K pixels between two cell centres take the same
// weights (w = (2j + 1)·128/K, as CellCoordinate gives), and the half cells
// at either end the end cells' values.
template <int K>
void ExpandRow(const uint8_t* __restrict t, int cells, uint8_t* __restrict out) {
  static_assert(K % 2 == 0);
  uint16_t wb[K], wa[K];
  for (int j = 0; j < K; ++j) {
    wb[j] = static_cast<uint16_t>(((2 * j + 1) * 256 + K) / (2 * K));
    wa[j] = static_cast<uint16_t>(256 - wb[j]);
  }
  std::fill(out, out + K / 2, t[0]);
  for (int c = 0; c + 1 < cells; ++c) {
    uint8_t* o = out + c * K + K / 2;
    const uint16_t a = t[c], b = t[c + 1];
    for (int j = 0; j < K; ++j) {
      o[j] = static_cast<uint8_t>(static_cast<uint16_t>(a * wa[j] + b * wb[j] + 128) >> 8);
    }
  }
  std::fill(out + (cells - 1) * K + K / 2, out + cells * K, t[cells - 1]);
}

}  // namespace

void CellRowExpander::Expand(const cv::Mat& cells, int cell_px, int width, cv::Mat& expanded) {
  const int n = cells.cols;
  if (columns_.size() != static_cast<size_t>(width) || columns_cells_ != n ||
      columns_cell_px_ != cell_px) {
    columns_.resize(static_cast<size_t>(width));
    for (int u = 0; u < width; ++u) {
      Column& c = columns_[static_cast<size_t>(u)];
      CellCoordinate(u, cell_px, n, c.c0, c.c1, c.w);
    }
    columns_cells_ = n;
    columns_cell_px_ = cell_px;
  }
  expanded.create(cells.rows, width, CV_8UC1);
  for (int r = 0; r < cells.rows; ++r) {
    const auto* t = cells.ptr<uint8_t>(r);
    auto* out = expanded.ptr<uint8_t>(r);
    if (width == n * cell_px) {
      switch (cell_px) {
        case 4: ExpandRow<4>(t, n, out); continue;
        case 8: ExpandRow<8>(t, n, out); continue;
        case 16: ExpandRow<16>(t, n, out); continue;
        default: break;
      }
    }
    for (int u = 0; u < width; ++u) {
      const Column& c = columns_[static_cast<size_t>(u)];
      out[u] = Interpolate(t[c.c0], t[c.c1], c.w);
    }
  }
}

}  // namespace plantscale::vision
