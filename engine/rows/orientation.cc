#include "engine/rows/orientation.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "engine/common/check.h"
#include "engine/common/vectorise.h"

namespace plantscale::rows {
namespace {

// Scales in pixels of the plant image (the detector's Hough resolution,
// 128 columns): the gradient after a slight blur, the tensor averaged over
// a few pixels, then sampled every kCellPx.
constexpr double kGradientSigma = 0.6;
constexpr double kTensorSigma = 1.2;
constexpr int kCellPx = 2;
// Cells with less gradient energy than this fraction of the strongest, or
// less coherence² than kMinWeight, carry no direction.
constexpr double kMinEnergyFraction = 1e-3;
constexpr double kMinWeight = 0.05;

// weight · (sin^16 − chance) of one cell; 0 at or above the vanishing point.
inline float Term(float u, float dv, float nu, float nv, float weight, float g, float c) {
  constexpr auto kChance = static_cast<float>(OrientationField::kChance);
  constexpr float kMinShrink = 0.05F;
  const float shrink = 1.0F - g * dv;
  // Branch-free (the loop vectorises): a cell at or above the vanishing
  // point gets weight 0 and a harmless divisor.
  const float below = static_cast<float>(shrink > kMinShrink);
  // The row line through the cell runs along (du/dΔv, 1) = (c − g·s, 1).
  const float slope = c - g * (u - c * dv) / std::max(shrink, kMinShrink);
  const float along = nu * slope + nv;
  const float cos2 = along * along / (1.0F + slope * slope);
  float a = 1.0F - cos2;  // sin² of the angle between the gradient and the line
  a *= a;
  a *= a;
  a *= a;  // sin^16
  return below * weight * (a - kChance);
}

// Σ Term over the cells, in kLanes partial sums so that the loop vectorises
// without reassociating one float sum.
PLANTSCALE_VECTOR_CLONES
float SupportSum(const float* __restrict u, const float* __restrict dv, const float* __restrict nu,
                 const float* __restrict nv, const float* __restrict weight, size_t n, float g,
                 float c) {
  constexpr size_t kLanes = 8;
  float partial[kLanes] = {};
  size_t i = 0;
  for (; i + kLanes <= n; i += kLanes) {
    for (size_t k = 0; k < kLanes; ++k) {
      partial[k] += Term(u[i + k], dv[i + k], nu[i + k], nv[i + k], weight[i + k], g, c);
    }
  }
  float sum = 0.0F;
  for (; i < n; ++i) sum += Term(u[i], dv[i], nu[i], nv[i], weight[i], g, c);
  for (const float p : partial) sum += p;
  return sum;
}

}  // namespace

void OrientationField::Build(const cv::Mat& plant, double scale_u, double scale_v,
                             double v_bottom) {
  PLANTSCALE_CHECK(plant.type() == CV_32FC1 && !plant.empty(), "orientation needs CV_32FC1");
  for (std::vector<float>* v : {&u_, &dv_, &nu_, &nv_, &weight_}) v->clear();
  total_weight_ = 0.0;
  cv::GaussianBlur(plant, blurred_, cv::Size(0, 0), kGradientSigma);
  cv::Sobel(blurred_, gu_, CV_32F, 1, 0, 3);
  cv::Sobel(blurred_, gv_, CV_32F, 0, 1, 3);
  cv::multiply(gu_, gu_, juu_);
  cv::multiply(gu_, gv_, juv_);
  cv::multiply(gv_, gv_, jvv_);
  for (cv::Mat* j : {&juu_, &juv_, &jvv_}) cv::GaussianBlur(*j, *j, cv::Size(0, 0), kTensorSigma);
  double max_trace = 0.0;
  for (int y = kCellPx / 2; y < plant.rows; y += kCellPx) {
    for (int x = kCellPx / 2; x < plant.cols; x += kCellPx) {
      max_trace =
          std::max(max_trace, static_cast<double>(juu_.at<float>(y, x) + jvv_.at<float>(y, x)));
    }
  }
  if (max_trace <= 0.0) return;
  for (int y = kCellPx / 2; y < plant.rows; y += kCellPx) {
    for (int x = kCellPx / 2; x < plant.cols; x += kCellPx) {
      const double a = juu_.at<float>(y, x), b = juv_.at<float>(y, x), d = jvv_.at<float>(y, x);
      const double trace = a + d;
      if (trace < kMinEnergyFraction * max_trace) continue;
      const double coherence = std::sqrt((a - d) * (a - d) + 4.0 * b * b) / trace;
      const double weight = coherence * coherence;
      if (weight < kMinWeight) continue;
      // Gradient direction in (u, v down); Δv runs up.
      const double theta = 0.5 * std::atan2(2.0 * b, a - d);
      u_.push_back(static_cast<float>((x + 0.5) * scale_u));
      dv_.push_back(static_cast<float>(v_bottom - (y + 0.5) * scale_v));
      nu_.push_back(static_cast<float>(std::cos(theta)));
      nv_.push_back(static_cast<float>(-std::sin(theta)));
      weight_.push_back(static_cast<float>(weight));
      total_weight_ += weight;
    }
  }
}

double OrientationField::Support(double g, double c) const {
  if (total_weight_ <= 0.0) return 0.0;
  const float sum = SupportSum(u_.data(), dv_.data(), nu_.data(), nv_.data(), weight_.data(),
                               u_.size(), static_cast<float>(g), static_cast<float>(c));
  return std::max(0.0, static_cast<double>(sum) / total_weight_);
}

}  // namespace plantscale::rows
