#pragma once
// Bilinear interpolation of a grid of cells back to pixels (the local
// threshold's soil level, soil growth's thresholds): a cell of `cell_px`
// pixels holds its value at its centre, pixels between two centres take
// both in proportion (weights in 256ths), pixels beyond the outer centres
// the outer value. First along u, one cell row at a time (Expand), then
// along v between two expanded rows (CellCoordinate of the pixel row).

#include <opencv2/core.hpp>
#include <cstdint>
#include <vector>

namespace plantscale::vision {

// The cells c0 ≤ c1 (of `cells`) either side of pixel i's centre and the
// weight of c1 in 256ths.
void CellCoordinate(int i, int cell_px, int cells, int& c0, int& c1, int& w256);

// (a·(256 − w) + b·w + 128) / 256 in 16-bit arithmetic (≤ 65408).
inline uint8_t Interpolate(uint8_t a, uint8_t b, int w256) {
  return static_cast<uint8_t>(
      static_cast<uint16_t>(a * (256 - w256) + b * w256 + 128) >> 8);
}

class CellRowExpander {
 public:
  // expanded (CV_8UC1, cells.rows × width): each row of `cells` (CV_8UC1)
  // interpolated along u to `width` pixels. The weights are kept between
  // calls of the same width and cell count.
  void Expand(const cv::Mat& cells, int cell_px, int width, cv::Mat& expanded);

 private:
  struct Column {
    int c0, c1, w;  // neighbouring cell columns and the weight of c1 (/256)
  };
  std::vector<Column> columns_;
  int columns_cells_ = 0, columns_cell_px_ = 0;
};

}  // namespace plantscale::vision
