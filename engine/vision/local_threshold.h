#pragma once
// plantscale's own plant threshold for near-infrared (or colour-index)
// images: the soil level is estimated locally and every pixel is compared
// with a gain times that level, O = 255 where I >= α·B(u, v).
//
// Why: Hague's adaptive threshold (eq. 2.15) interpolates one brightness
// gradient down the whole image, so a hard-edged vehicle shadow (thesis
// sequence D) or a bright patch shifts the threshold for everything. Here
// B(u, v) is a grey-level opening of the block-mean image: the opening
// removes plants (bright structures narrower than the structuring element)
// and keeps large dark regions such as a shadow with their edges in place
// (an opening preserves a straight step edge), so soil in sun and soil in
// shadow are each compared with their own level.
//
// Cost: one area-averaging pass down to cells, a tiny opening, one
// bilinear pass back up and one compare; the cell images are a few
// thousand pixels. Buffers are kept, so frames after the first allocate
// nothing.

#include <opencv2/core.hpp>
#include <vector>

#include "engine/common/options.h"
#include "engine/vision/cell_grid.h"

namespace plantscale::vision {

struct LocalThresholdOptions {
  double gain = 2.3;         // α: plant where I >= α·B (set at Φ ≈ 3.6 on presets A–D, seed 100)
  int cell_px = 8;           // block size of the soil-level grid
  int opening_cells = 21;    // structuring element, cells (odd): wider than any plant
  double min_level = 4.0;    // floor of B in grey levels (black images)

  OptionErrors Validate() const;
};

class LocalThreshold {
 public:
  explicit LocalThreshold(const LocalThresholdOptions& options = {});

  // Estimates B for `grey` (CV_8UC1) and writes the 255/0 mask.
  void Apply(const cv::Mat& grey, cv::Mat& mask);
  // The mask at another gain over the soil level of the last Apply or
  // Estimate (of the same image). cell_thresholds() stays the last Apply's.
  void ApplyAtGain(const cv::Mat& grey, double gain, cv::Mat& mask);
  // Estimates the soil level B (on the cell grid) of `grey`.
  void Estimate(const cv::Mat& grey);
  // Score I / B (CV_32FC1) of the last estimated image: thresholding it at
  // `gain` gives the mask (for ROC curves over the gain).
  void Score(const cv::Mat& grey, cv::Mat& score);
  // α·B on the cell grid (CV_8UC1) of the last Apply.
  const cv::Mat& cell_thresholds() const { return threshold_cells_; }
  const LocalThresholdOptions& options() const { return options_; }

 private:
  LocalThresholdOptions options_;
  void CellMeans(const cv::Mat& grey);
  // α·B of every cell row (gain_lut: α·max(B, min_level) per byte B) into
  // `cells`, interpolated along u to full width into `expanded`.
  void ExpandThresholdRows(int width, const cv::Mat& gain_lut, cv::Mat& cells, cv::Mat& expanded);
  void CompareRows(const cv::Mat& grey, const cv::Mat& expanded, cv::Mat& mask) const;

  cv::Mat cells_, eroded_, opened_, level_, threshold_cells_;
  cv::Mat gain_lut_;  // 1×256: α·max(B, min_level) as a byte
  cv::Mat other_lut_, other_cells_, other_expanded_;  // ApplyAtGain's
  std::vector<uint16_t> column_sums_;
  std::vector<uint8_t> extremum_buffer_;
  cv::Mat expanded_;  // CV_8UC1: α·B per cell row, interpolated along u
  CellRowExpander expander_;
};

}  // namespace plantscale::vision
