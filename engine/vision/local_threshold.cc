#include "engine/vision/local_threshold.h"

#include <algorithm>
#include <opencv2/imgproc.hpp>

#include "engine/common/check.h"
#include "engine/common/vectorise.h"
#include "engine/vision/cell_grid.h"

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

namespace {

// α·max(B, min_level) for every byte B, by the same OpenCV calls (cv::max,
// convertTo) the cell image would take.
void GainLut(double gain, double min_level, cv::Mat& lut) {
  cv::Mat ramp(1, 256, CV_8UC1), floored;
  for (int b = 0; b < 256; ++b) ramp.at<uint8_t>(0, b) = static_cast<uint8_t>(b);
  cv::max(ramp, min_level, floored);
  floored.convertTo(lut, CV_8U, gain);
}

// sums[u] += row[u] over one row (a cell row's column sums, 16 bits hold
// up to 257 rows of 255).
PLANTSCALE_VECTOR_CLONES
void AccumulateRow(const uint8_t* __restrict row, int width, uint16_t* __restrict sums) {
  for (int u = 0; u < width; ++u) sums[u] = static_cast<uint16_t>(sums[u] + row[u]);
}

template <bool kMin>
uint8_t Extreme(uint8_t a, uint8_t b) {
  return kMin ? std::min(a, b) : std::max(a, b);
}

// data[i] = min (kMin) or max of data[i + j·step] over j < window, for
// i < count; `data` holds count + (window − 1)·step entries and is
// overwritten. Sparse-table doubling: ⌊log2 window⌋ + 1 passes, each one
// vectorised loop over the whole buffer.
template <bool kMin>
void WindowExtremum(uint8_t* data, size_t count, size_t window, size_t step) {
  size_t span = 1, valid = count + (window - 1) * step;
  while (2 * span <= window) {
    valid -= span * step;
    const size_t offset = span * step;
    for (size_t i = 0; i < valid; ++i) data[i] = Extreme<kMin>(data[i], data[i + offset]);
    span *= 2;
  }
  // data[i] covers `span` entries; two overlapping spans cover the window.
  const size_t rest = (window - span) * step;
  if (rest == 0) return;
  for (size_t i = 0; i < count; ++i) data[i] = Extreme<kMin>(data[i], data[i + rest]);
}

// Rectangular erosion (kMin) or dilation of `in` into `out` (both CV_8UC1,
// the same size), separable, borders replicated as cv::BORDER_REPLICATE.
template <bool kMin>
void Extremum(const cv::Mat& in, int r, std::vector<uint8_t>& buffer, cv::Mat& out) {
  const int w = in.cols, h = in.rows, stride = w + 2 * r;
  const auto window = static_cast<size_t>(2 * r + 1);
  buffer.resize(static_cast<size_t>(std::max(h * stride, (h + 2 * r) * w)));
  out.create(in.size(), CV_8UC1);
  // Along u: rows padded by r replicated pixels at each end, one after the other.
  for (int v = 0; v < h; ++v) {
    const auto* row = in.ptr<uint8_t>(v);
    uint8_t* p = buffer.data() + static_cast<size_t>(v) * static_cast<size_t>(stride);
    std::fill(p, p + r, row[0]);
    std::copy(row, row + w, p + r);
    std::fill(p + r + w, p + stride, row[w - 1]);
  }
  WindowExtremum<kMin>(buffer.data(), static_cast<size_t>((h - 1) * stride + w), window, 1);
  for (int v = 0; v < h; ++v) {
    const uint8_t* p = buffer.data() + static_cast<size_t>(v) * static_cast<size_t>(stride);
    std::copy(p, p + w, out.ptr<uint8_t>(v));
  }
  // Along v: r replicated rows above and below.
  for (int j = 0; j < h + 2 * r; ++j) {
    const auto* row = out.ptr<uint8_t>(std::clamp(j - r, 0, h - 1));
    std::copy(row, row + w, buffer.data() + static_cast<size_t>(j) * static_cast<size_t>(w));
  }
  WindowExtremum<kMin>(buffer.data(), static_cast<size_t>(h * w), window, static_cast<size_t>(w));
  for (int v = 0; v < h; ++v) {
    const uint8_t* p = buffer.data() + static_cast<size_t>(v) * static_cast<size_t>(w);
    std::copy(p, p + w, out.ptr<uint8_t>(v));
  }
}

// out = 255 where in >= the threshold interpolated between rows a and b with
// weight w/256. 16-bit arithmetic: a·(256 − w) + b·w + 128 ≤ 65408.
PLANTSCALE_VECTOR_CLONES
void CompareRow(const uint8_t* __restrict in, const uint8_t* __restrict a,
                const uint8_t* __restrict b, int w, uint8_t* __restrict out, int width) {
  const auto wb = static_cast<uint16_t>(w), wa = static_cast<uint16_t>(256 - w);
  for (int u = 0; u < width; ++u) {
    const auto sum = static_cast<uint16_t>(static_cast<uint16_t>(a[u] * wa) +
                                           static_cast<uint16_t>(b[u] * wb) + 128);
    const auto t = static_cast<uint8_t>(sum >> 8);
    out[u] = in[u] >= t ? 255 : 0;
  }
}

}  // namespace

LocalThreshold::LocalThreshold(const LocalThresholdOptions& options) : options_(options) {
  ThrowIfInvalid("local threshold options", options_.Validate());
  GainLut(options_.gain, options_.min_level, gain_lut_);
}

// Block means of `grey` on the cell grid: whole cells rounded as INTER_AREA
// rounds them for an integer factor (the same bytes), INTER_AREA itself
// otherwise.
void LocalThreshold::CellMeans(const cv::Mat& grey) {
  const int cell = options_.cell_px;
  const cv::Size small(std::max(1, grey.cols / cell), std::max(1, grey.rows / cell));
  if (grey.cols % cell != 0 || grey.rows % cell != 0 || cell > 16) {
    cv::resize(grey, cells_, small, 0.0, 0.0, cv::INTER_AREA);
    return;
  }
  cells_.create(small, CV_8UC1);
  column_sums_.resize(static_cast<size_t>(grey.cols));
  const float inv_area = 1.0f / static_cast<float>(cell * cell);  // INTER_AREA's own rounding
  for (int r = 0; r < small.height; ++r) {
    std::fill(column_sums_.begin(), column_sums_.end(), uint16_t{0});
    for (int k = 0; k < cell; ++k) {
      AccumulateRow(grey.ptr<uint8_t>(r * cell + k), grey.cols, column_sums_.data());
    }
    // Sums of `cell` neighbours by doubling when the cell is a power of two
    // (vectorised; ≤ 16² · 255 fits 16 bits), else one cell at a time.
    uint16_t* s = column_sums_.data();
    int summed = 1;
    for (int span = 1; 2 * span <= cell && cell % (2 * span) == 0; span *= 2, summed *= 2) {
      for (int u = 0; u + span < grey.cols; ++u) s[u] = static_cast<uint16_t>(s[u] + s[u + span]);
    }
    auto* out = cells_.ptr<uint8_t>(r);
    for (int c = 0; c < small.width; ++c) {
      int sum = 0;
      for (int k = 0; k < cell; k += summed) sum += s[c * cell + k];
      out[c] = cv::saturate_cast<uint8_t>(static_cast<float>(sum) * inv_area);
    }
  }
}

void LocalThreshold::Estimate(const cv::Mat& grey) {
  PLANTSCALE_CHECK(grey.type() == CV_8UC1 && !grey.empty(), "local threshold needs CV_8UC1");
  CellMeans(grey);
  // Opening (erosion, then dilation) with the square structuring element.
  const int r = options_.opening_cells / 2;
  Extremum<true>(cells_, r, extremum_buffer_, eroded_);
  Extremum<false>(eroded_, r, extremum_buffer_, opened_);
  cv::max(opened_, options_.min_level, opened_);
}

// α·B of every cell row, linearly interpolated along u to full width.
void LocalThreshold::ExpandThresholdRows(int width, const cv::Mat& gain_lut, cv::Mat& cells_out,
                                         cv::Mat& expanded) {
  cv::LUT(opened_, gain_lut, cells_out);
  expander_.Expand(cells_out, options_.cell_px, width, expanded);
}

void LocalThreshold::CompareRows(const cv::Mat& grey, const cv::Mat& expanded,
                                 cv::Mat& mask) const {
  mask.create(grey.size(), CV_8UC1);
  for (int v = 0; v < grey.rows; ++v) {
    int r0, r1, w;
    CellCoordinate(v, options_.cell_px, expanded.rows, r0, r1, w);
    CompareRow(grey.ptr<uint8_t>(v), expanded.ptr<uint8_t>(r0), expanded.ptr<uint8_t>(r1), w,
               mask.ptr<uint8_t>(v), grey.cols);
  }
}

void LocalThreshold::Apply(const cv::Mat& grey, cv::Mat& mask) {
  Estimate(grey);
  ExpandThresholdRows(grey.cols, gain_lut_, threshold_cells_, expanded_);
  CompareRows(grey, expanded_, mask);
}

void LocalThreshold::ApplyAtGain(const cv::Mat& grey, double gain, cv::Mat& mask) {
  PLANTSCALE_CHECK(!opened_.empty(), "ApplyAtGain after Apply");
  PLANTSCALE_CHECK(gain > 0.0, "gain must be > 0");
  GainLut(gain, options_.min_level, other_lut_);
  ExpandThresholdRows(grey.cols, other_lut_, other_cells_, other_expanded_);
  CompareRows(grey, other_expanded_, mask);
}

void LocalThreshold::Score(const cv::Mat& grey, cv::Mat& score) {
  PLANTSCALE_CHECK(!opened_.empty(), "Score after Estimate");
  cv::resize(opened_, level_, grey.size(), 0.0, 0.0, cv::INTER_LINEAR);
  cv::divide(grey, level_, score, 1.0, CV_32F);
}

}  // namespace plantscale::vision
