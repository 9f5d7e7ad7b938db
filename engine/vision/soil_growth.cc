#include "engine/vision/soil_growth.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <string>

#include "engine/vision/row_bits.h"

namespace plantscale::vision {

OptionErrors SoilGrowthOptions::Validate() const {
  OptionErrors e;
  RequireInRange(e, "z", z, 0.0, 20.0);
  RequireInRange(e, "trim_z", trim_z, 0.0, 20.0);
  if (reach_px < 1 || reach_px > 50) e.push_back({"reach_px", "must be in [1, 50]"});
  if (cell_px < 4 || cell_px > 64 || !std::has_single_bit(static_cast<unsigned>(cell_px))) {
    e.push_back({"cell_px", "must be a power of two in [4, 64]"});
  }
  if (window_cells < 1 || window_cells > 101 || window_cells % 2 == 0) {
    e.push_back({"window_cells", "must be odd and in [1, 101]"});
  }
  if (clearance_px < 0 || clearance_px > 50) e.push_back({"clearance_px", "must be in [0, 50]"});
  if (min_soil_samples < 2) e.push_back({"min_soil_samples", "must be >= 2"});
  if (min_area_px < 1) e.push_back({"min_area_px", "must be >= 1"});
  if (join_min_area_px < 0) e.push_back({"join_min_area_px", "must be >= 0"});
  return e;
}

namespace {

// Soil samples: every second pixel of every fourth row (a 7-cell window of
// 8 px holds up to 392). With every second row the step took 455 µs on the
// benchmark frame, 374 µs with every fourth.
constexpr int kRowStride = 4;

const SoilGrowthOptions& Validated(const SoilGrowthOptions& options) {
  ThrowIfInvalid("soil growth options", options.Validate());
  return options;
}

// out = in dilated by one pixel along v (rows of `words` words).
void StepAlongV(const std::vector<uint64_t>& in, size_t words, int rows,
                std::vector<uint64_t>& out) {
  out.resize(in.size());
  for (int v = 0; v < rows; ++v) {
    const size_t row = static_cast<size_t>(v) * words;
    for (size_t w = 0; w < words; ++w) {
      uint64_t x = in[row + w];
      if (v > 0) x |= in[row - words + w];
      if (v + 1 < rows) x |= in[row + words + w];
      out[row + w] = x;
    }
  }
}

// out(r, c) = the sum of in over rows r ± h and columns c ± h within the
// grid (CV_64F), from a summed-area table (`table`, reused): a few
// operations per cell.
void BoxSum(const cv::Mat& in, int h, std::vector<double>& table, cv::Mat& out) {
  const int rows = in.rows, cols = in.cols;
  table.assign(static_cast<size_t>(rows + 1) * static_cast<size_t>(cols + 1), 0.0);
  const auto at = [&](int r, int c) -> double& {
    return table[static_cast<size_t>(r) * static_cast<size_t>(cols + 1) + static_cast<size_t>(c)];
  };
  for (int r = 0; r < rows; ++r) {
    const double* x = in.ptr<double>(r);
    double row_sum = 0.0;
    for (int c = 0; c < cols; ++c) {
      row_sum += x[c];
      at(r + 1, c + 1) = at(r, c + 1) + row_sum;
    }
  }
  out.create(rows, cols, CV_64F);
  for (int r = 0; r < rows; ++r) {
    const int r0 = std::max(r - h, 0), r1 = std::min(r + h + 1, rows);
    double* o = out.ptr<double>(r);
    for (int c = 0; c < cols; ++c) {
      const int c0 = std::max(c - h, 0), c1 = std::min(c + h + 1, cols);
      o[c] = at(r1, c1) - at(r0, c1) - at(r1, c0) + at(r0, c0);
    }
  }
}

}  // namespace

SoilGrower::SoilGrower(const SoilGrowthOptions& options) : options_(Validated(options)) {}

void SoilGrower::ClearanceBits(int width, int height) {
  // The mask dilated by a (2c + 1)² square: c steps along u, then along v.
  const auto words = static_cast<size_t>((width + 63) / 64);
  near_bits_ = mask_bits_;
  for (int k = 0; k < options_.clearance_px; ++k) {
    detail::StepAlongU<true>(near_bits_, static_cast<int>(words), height, width, scratch_);
    near_bits_.swap(scratch_);
  }
  for (int k = 0; k < options_.clearance_px; ++k) {
    StepAlongV(near_bits_, words, height, scratch_);
    near_bits_.swap(scratch_);
  }
}

void SoilGrower::SoilStatistics(const cv::Mat* limit) {
  n_.create(cells_h_, cells_w_, CV_64F);
  s1_.create(cells_h_, cells_w_, CV_64F);
  s2_.create(cells_h_, cells_w_, CV_64F);
  n_.setTo(0.0);
  s1_.setTo(0.0);
  s2_.setTo(0.0);
  const int width = smooth_.cols, height = smooth_.rows, cell = options_.cell_px;
  const auto words = static_cast<size_t>((width + 63) / 64);
  // Every second pixel of every fourth row.
  for (int v = 0; v < height; v += kRowStride) {
    const uint8_t* x = smooth_.ptr<uint8_t>(v);
    const uint64_t* near = near_bits_.data() + static_cast<size_t>(v) * words;
    const int r = v / cell;
    double* n = n_.ptr<double>(r);
    double* s1 = s1_.ptr<double>(r);
    double* s2 = s2_.ptr<double>(r);
    const double* top = limit ? limit->ptr<double>(r) : nullptr;
    for (int c = 0; c < cells_w_; ++c) {
      // The cell's samples (its even pixels) that are clear of the mask, as
      // bits: a cell lies within one word, since cell_px is a power of two.
      const int u0 = c * cell;
      const uint64_t word = near[u0 / 64] >> (u0 % 64);
      const int span = std::min(cell, width - u0);
      const uint64_t cell_bits = span == 64 ? ~uint64_t{0} : (uint64_t{1} << span) - 1;
      uint64_t clear = ~word & cell_bits & 0x5555555555555555ULL;
      if (clear == 0) continue;
      int count = 0, sum = 0, sum_sq = 0;
      const int cap = top ? static_cast<int>(std::floor(std::min(top[c], 256.0))) : 256;
      while (clear != 0) {
        const int value = x[u0 + std::countr_zero(clear)];
        clear &= clear - 1;
        if (value > cap) continue;
        ++count;
        sum += value;
        sum_sq += value * value;
      }
      n[c] += count;
      s1[c] += sum;
      s2[c] += sum_sq;
    }
  }
  BoxSum(n_, options_.window_cells / 2, table_, box_n_);
  BoxSum(s1_, options_.window_cells / 2, table_, box_s1_);
  BoxSum(s2_, options_.window_cells / 2, table_, box_s2_);
  mean_.create(cells_h_, cells_w_, CV_64F);
  sd_.create(cells_h_, cells_w_, CV_64F);
  for (int r = 0; r < cells_h_; ++r) {
    const double* n = box_n_.ptr<double>(r);
    const double* s1 = box_s1_.ptr<double>(r);
    const double* s2 = box_s2_.ptr<double>(r);
    double* mean = mean_.ptr<double>(r);
    double* sd = sd_.ptr<double>(r);
    for (int c = 0; c < cells_w_; ++c) {
      if (n[c] < options_.min_soil_samples) {
        mean[c] = sd[c] = -1.0;  // no statistics
        continue;
      }
      mean[c] = s1[c] / n[c];
      sd[c] = std::max(std::sqrt(std::max(s2[c] / n[c] - mean[c] * mean[c], 0.0)), 1.0);
    }
  }
}

void SoilGrower::Thresholds() {
  // Per cell: ceil(μ + z·σ), 255 where there are no statistics or it is at
  // least 255 (then no pixel is a candidate: valid_ below).
  cell_threshold_.create(cells_h_, cells_w_, CV_8U);
  for (int r = 0; r < cells_h_; ++r) {
    const double* mean = mean_.ptr<double>(r);
    const double* sd = sd_.ptr<double>(r);
    uint8_t* t = cell_threshold_.ptr<uint8_t>(r);
    for (int c = 0; c < cells_w_; ++c) {
      const double level = std::ceil(mean[c] + options_.z * sd[c]);
      t[c] = mean[c] < 0.0 || level >= 255.0 ? uint8_t{255} : static_cast<uint8_t>(level);
    }
  }
  const int cell = options_.cell_px;
  cv::resize(cell_threshold_, threshold_, cv::Size(cells_w_ * cell, cells_h_ * cell), 0.0, 0.0,
             cv::INTER_LINEAR);
  const cv::Mat t = threshold_(cv::Rect(0, 0, smooth_.cols, smooth_.rows));
  cv::compare(smooth_, t, candidate_, cv::CMP_GE);
  cv::compare(t, 255, valid_, cv::CMP_LT);
  cv::bitwise_and(candidate_, valid_, candidate_);
}

void SoilGrower::GrowBits(int width, int height) {
  const auto words = static_cast<size_t>((width + 63) / 64);
  candidate_bits_.resize(mask_bits_.size());
  for (int v = 0; v < height; ++v) {
    uint64_t* c = candidate_bits_.data() + static_cast<size_t>(v) * words;
    detail::RowBits(candidate_.ptr<uint8_t>(v), width, c);
    const uint64_t* m = mask_bits_.data() + static_cast<size_t>(v) * words;
    for (size_t w = 0; w < words; ++w) c[w] &= ~m[w];
  }
  // Geodesic growth: one 3×3 dilation a step, kept to the seeds and the
  // candidates.
  grown_bits_ = seed_bits_;
  for (int k = 0; k < options_.reach_px; ++k) {
    detail::StepAlongU<true>(grown_bits_, static_cast<int>(words), height, width, scratch_);
    StepAlongV(scratch_, words, height, grown_bits_);
    for (size_t i = 0; i < grown_bits_.size(); ++i) {
      grown_bits_[i] &= seed_bits_[i] | candidate_bits_[i];
    }
  }
}

int SoilGrower::Grow(const cv::Mat& plant, cv::Mat& mask) {
  if (plant.type() != CV_8UC1 || mask.type() != CV_8UC1 || plant.size() != mask.size()) {
    throw DataError("soil growth needs a CV_8UC1 plant image and mask of one size (got " +
                    std::to_string(plant.cols) + "x" + std::to_string(plant.rows) + " type " +
                    std::to_string(plant.type()) + " and " + std::to_string(mask.cols) + "x" +
                    std::to_string(mask.rows) + " type " + std::to_string(mask.type()) + ")");
  }
  // The mask's blobs (8-connected), labelled first so that mask_runs()
  // hold this frame's whatever follows.
  const int width = mask.cols, height = mask.rows;
  const auto words = static_cast<size_t>((width + 63) / 64);
  mask_bits_.resize(words * static_cast<size_t>(height));
  for (int v = 0; v < height; ++v) {
    detail::RowBits(mask.ptr<uint8_t>(v), width, mask_bits_.data() + static_cast<size_t>(v) * words);
  }
  keep_.LabelMask(mask_bits_, width, height);
  if (mask.empty() || !options_.enabled()) return 0;

  cv::GaussianBlur(plant, smooth_, cv::Size(3, 3), 0.0, 0.0, cv::BORDER_REPLICATE);
  cells_w_ = (width + options_.cell_px - 1) / options_.cell_px;
  cells_h_ = (height + options_.cell_px - 1) / options_.cell_px;
  ClearanceBits(width, height);
  SoilStatistics(nullptr);
  if (options_.trim_z > 0.0) {
    limit_.create(cells_h_, cells_w_, CV_64F);
    for (int r = 0; r < cells_h_; ++r) {
      const double* mean = mean_.ptr<double>(r);
      const double* sd = sd_.ptr<double>(r);
      double* top = limit_.ptr<double>(r);
      for (int c = 0; c < cells_w_; ++c) {
        top[c] = mean[c] < 0.0 ? 256.0 : mean[c] + options_.trim_z * sd[c];
      }
    }
    SoilStatistics(&limit_);
  }
  Thresholds();

  // Seeds: the blobs of at least min_area_px pixels.
  const std::vector<detail::RowRun>& runs = keep_.runs();
  const std::vector<int>& parent = keep_.parent();
  area_.assign(runs.size(), 0);
  for (size_t i = 0; i < runs.size(); ++i) {
    area_[static_cast<size_t>(parent[i])] += runs[i].u_end - runs[i].u_begin;
  }
  seed_bits_.assign(mask_bits_.size(), 0);
  for (size_t i = 0; i < runs.size(); ++i) {
    const auto root = static_cast<size_t>(parent[i]);
    if (area_[root] < options_.min_area_px) continue;
    detail::SetBits(seed_bits_.data() + static_cast<size_t>(runs[i].v) * words, runs[i].u_begin,
                    runs[i].u_end);
  }
  GrowBits(width, height);

  if (options_.join_min_area_px > 0) {
    small_.assign(runs.size(), 0);
    for (size_t i = 0; i < runs.size(); ++i) {
      const auto root = static_cast<size_t>(parent[i]);
      small_[root] = area_[root] < options_.join_min_area_px ? 1 : 0;
    }
    for (size_t i = 0; i < grown_bits_.size(); ++i) grown_bits_[i] |= mask_bits_[i];
    return keep_.Add(mask_bits_, grown_bits_, nullptr, mask, &small_);
  }
  int added = 0;
  for (int v = 0; v < height; ++v) {
    const size_t row = static_cast<size_t>(v) * words;
    uint8_t* m = mask.ptr<uint8_t>(v);
    for (size_t w = 0; w < words; ++w) {
      uint64_t fresh = grown_bits_[row + w] & ~mask_bits_[row + w];
      while (fresh != 0) {
        m[64 * w + static_cast<size_t>(std::countr_zero(fresh))] = 255;
        fresh &= fresh - 1;
        ++added;
      }
    }
  }
  return added;
}

}  // namespace plantscale::vision
