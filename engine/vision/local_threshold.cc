#include "engine/vision/local_threshold.h"

#include <algorithm>
#include <opencv2/imgproc.hpp>

#include "engine/common/check.h"

namespace plantscale::vision {

OptionErrors LocalThresholdOptions::Validate() const {
  OptionErrors e;
  RequirePositive(e, "gain", gain);
  if (cell_px < 1) e.push_back({"cell_px", "must be >= 1"});
  if (opening_cells < 1 || opening_cells % 2 == 0) {
    e.push_back({"opening_cells", "must be odd and >= 1"});
  }
  RequireNonNegative(e, "min_level", min_level);
  return e;
}

LocalThreshold::LocalThreshold(const LocalThresholdOptions& options) : options_(options) {
  ThrowIfInvalid("local threshold options", options_.Validate());
  kernel_ = cv::getStructuringElement(cv::MORPH_RECT,
                                      cv::Size(options_.opening_cells, options_.opening_cells));
}

void LocalThreshold::Estimate(const cv::Mat& grey) {
  PLANTSCALE_CHECK(grey.type() == CV_8UC1 && !grey.empty(), "local threshold needs CV_8UC1");
  const cv::Size small(std::max(1, grey.cols / options_.cell_px),
                       std::max(1, grey.rows / options_.cell_px));
  cv::resize(grey, cells_, small, 0.0, 0.0, cv::INTER_AREA);
  cv::morphologyEx(cells_, opened_, cv::MORPH_OPEN, kernel_, cv::Point(-1, -1), 1,
                   cv::BORDER_REPLICATE);
  cv::max(opened_, options_.min_level, opened_);
}

namespace {

// Fractional position of pixel centre i among cell centres of `cell` pixels.
void CellCoordinate(int i, int cell, int cells, int& c0, int& c1, int& w256) {
  const double c = (i + 0.5) / cell - 0.5;
  const double clamped = std::clamp(c, 0.0, static_cast<double>(cells - 1));
  c0 = static_cast<int>(clamped);
  c1 = std::min(c0 + 1, cells - 1);
  w256 = static_cast<int>((clamped - c0) * 256.0 + 0.5);
}

// out = 255 where in >= the threshold interpolated between rows a and b with
// weight w/256 (vectorised by GCC: this file is compiled with -O3).
void CompareRow(const uint8_t* in, const uint8_t* a, const uint8_t* b, int w, uint8_t* out,
                int width) {
  const auto wb = static_cast<uint16_t>(w), wa = static_cast<uint16_t>(256 - w);
  for (int u = 0; u < width; ++u) {
    const auto t = static_cast<uint16_t>((a[u] * wa + b[u] * wb + 128) >> 8);
    out[u] = in[u] >= t ? 255 : 0;
  }
}

}  // namespace

// α·B of every cell row, linearly interpolated along u to full width.
void LocalThreshold::ExpandThresholdRows(int width) {
  opened_.convertTo(threshold_cells_, CV_8U, options_.gain);
  const int cells = threshold_cells_.cols;
  if (columns_.size() != static_cast<size_t>(width) || columns_cells_ != cells) {
    columns_.resize(static_cast<size_t>(width));
    for (int u = 0; u < width; ++u) {
      Column& c = columns_[static_cast<size_t>(u)];
      CellCoordinate(u, options_.cell_px, cells, c.c0, c.c1, c.w);
    }
    columns_cells_ = cells;
  }
  expanded_.create(threshold_cells_.rows, width, CV_8UC1);
  for (int r = 0; r < threshold_cells_.rows; ++r) {
    const auto* t = threshold_cells_.ptr<uint8_t>(r);
    auto* out = expanded_.ptr<uint8_t>(r);
    for (int u = 0; u < width; ++u) {
      const Column& c = columns_[static_cast<size_t>(u)];
      out[u] = static_cast<uint8_t>((t[c.c0] * (256 - c.w) + t[c.c1] * c.w + 128) >> 8);
    }
  }
}

void LocalThreshold::Apply(const cv::Mat& grey, cv::Mat& mask) {
  Estimate(grey);
  ExpandThresholdRows(grey.cols);
  mask.create(grey.size(), CV_8UC1);
  for (int v = 0; v < grey.rows; ++v) {
    int r0, r1, w;
    CellCoordinate(v, options_.cell_px, expanded_.rows, r0, r1, w);
    CompareRow(grey.ptr<uint8_t>(v), expanded_.ptr<uint8_t>(r0), expanded_.ptr<uint8_t>(r1), w,
               mask.ptr<uint8_t>(v), grey.cols);
  }
}

void LocalThreshold::Score(const cv::Mat& grey, cv::Mat& score) {
  PLANTSCALE_CHECK(!opened_.empty(), "Score after Estimate");
  cv::resize(opened_, level_, grey.size(), 0.0, 0.0, cv::INTER_LINEAR);
  cv::divide(grey, level_, score, 1.0, CV_32F);
}

}  // namespace plantscale::vision
