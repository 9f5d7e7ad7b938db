#include "engine/vision/soil_growth.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <opencv2/imgproc.hpp>
#include <string>

#include "engine/vision/row_bits.h"

namespace plantscale::vision {

OptionErrors SoilGrowthOptions::Validate() const {
  OptionErrors e;
  RequireInRange(e, "z", z, 0.0, 20.0);
  if (reach_px < 1 || reach_px > 50) e.push_back({"reach_px", "must be in [1, 50]"});
  if (window_px < 3 || window_px > 1001 || window_px % 2 == 0) {
    e.push_back({"window_px", "must be odd and in [3, 1001]"});
  }
  if (clearance_px < 0 || clearance_px > 50) e.push_back({"clearance_px", "must be in [0, 50]"});
  if (min_soil_samples < 2) e.push_back({"min_soil_samples", "must be >= 2"});
  if (min_area_px < 1) e.push_back({"min_area_px", "must be >= 1"});
  return e;
}

namespace {
const SoilGrowthOptions& Validated(const SoilGrowthOptions& options) {
  ThrowIfInvalid("soil growth options", options.Validate());
  return options;
}
}  // namespace

SoilGrower::SoilGrower(const SoilGrowthOptions& options)
    : options_(Validated(options)),
      kernel_(cv::getStructuringElement(
          cv::MORPH_RECT, cv::Size(2 * options.clearance_px + 1, 2 * options.clearance_px + 1))) {}

void SoilGrower::SoilStatistics(const cv::Mat& mask) {
  // Soil samples: pixels further than clearance_px (Chebyshev) from the mask.
  if (options_.clearance_px > 0) {
    cv::dilate(mask, near_, kernel_);
  } else {
    mask.copyTo(near_);
  }
  // weight 1 on soil samples, 0 elsewhere; value and square where weighted.
  cv::compare(near_, 0, weight_, cv::CMP_EQ);
  weight_.convertTo(weight_, CV_64F, 1.0 / 255.0);
  smooth_.convertTo(value_, CV_64F);
  cv::multiply(value_, weight_, value_);
  cv::multiply(value_, value_, square_);  // weight² = weight
  const cv::Size box(options_.window_px, options_.window_px);
  // Unnormalised box sums; pixels beyond the image count as nothing.
  cv::boxFilter(weight_, count_, CV_64F, box, cv::Point(-1, -1), false, cv::BORDER_CONSTANT);
  cv::boxFilter(value_, sum_, CV_64F, box, cv::Point(-1, -1), false, cv::BORDER_CONSTANT);
  cv::boxFilter(square_, sum_sq_, CV_64F, box, cv::Point(-1, -1), false, cv::BORDER_CONSTANT);
}

void SoilGrower::Candidates(const cv::Mat& mask) {
  candidate_.create(mask.size(), CV_8UC1);
  const double z = options_.z, min_n = options_.min_soil_samples - 0.5;
  for (int v = 0; v < mask.rows; ++v) {
    const uint8_t* m = mask.ptr<uint8_t>(v);
    const uint8_t* s = smooth_.ptr<uint8_t>(v);
    const double* n = count_.ptr<double>(v);
    const double* s1 = sum_.ptr<double>(v);
    const double* s2 = sum_sq_.ptr<double>(v);
    uint8_t* c = candidate_.ptr<uint8_t>(v);
    for (int u = 0; u < mask.cols; ++u) {
      c[u] = 0;
      if (m[u] != 0 || n[u] < min_n) continue;
      const double mean = s1[u] / n[u];
      const double sd = std::sqrt(std::max(s2[u] / n[u] - mean * mean, 0.0));
      if (s[u] >= mean + z * std::max(sd, 1.0)) c[u] = 255;
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
  SoilStatistics(mask);
  Candidates(mask);

  // Seeds: the blobs of at least min_area_px pixels.
  const std::vector<detail::RowRun>& runs = keep_.runs();
  const std::vector<int>& parent = keep_.parent();
  area_.assign(runs.size(), 0);
  for (size_t i = 0; i < runs.size(); ++i) {
    area_[static_cast<size_t>(parent[i])] += runs[i].u_end - runs[i].u_begin;
  }
  counted_.assign(runs.size(), 0);
  seeds_.create(mask.size(), CV_8UC1);
  seeds_.setTo(0);
  for (size_t i = 0; i < runs.size(); ++i) {
    const auto root = static_cast<size_t>(parent[i]);
    if (area_[root] < options_.min_area_px) continue;
    counted_[root] = 1;
    std::memset(seeds_.ptr<uint8_t>(runs[i].v) + runs[i].u_begin, 255,
                static_cast<size_t>(runs[i].u_end - runs[i].u_begin));
  }

  // Geodesic growth: one 3×3 dilation a step, kept to candidates (and the
  // seeds themselves).
  cv::bitwise_or(candidate_, seeds_, allowed_);
  seeds_.copyTo(grown_);
  const cv::Mat step = cv::getStructuringElement(cv::MORPH_RECT, cv::Size(3, 3));
  for (int k = 0; k < options_.reach_px; ++k) {
    cv::dilate(grown_, step_, step);
    cv::bitwise_and(step_, allowed_, grown_);
  }
  cv::bitwise_and(grown_, candidate_, grown_);  // the new pixels

  if (options_.refuse_joins) {
    cv::bitwise_or(grown_, mask, grown_);
    grown_bits_.resize(mask_bits_.size());
    for (int v = 0; v < height; ++v) {
      detail::RowBits(grown_.ptr<uint8_t>(v), width, grown_bits_.data() + static_cast<size_t>(v) * words);
    }
    return keep_.Add(mask_bits_, grown_bits_, &counted_, mask);
  }
  const int added = cv::countNonZero(grown_);
  cv::bitwise_or(mask, grown_, mask);
  return added;
}

}  // namespace plantscale::vision
