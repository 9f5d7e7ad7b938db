#include "engine/vision/threshold.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "engine/common/check.h"

namespace plantscale::vision {
namespace {

void CheckGrey(const cv::Mat& grey) {
  PLANTSCALE_CHECK(grey.type() == CV_8UC1 && !grey.empty(), "threshold input must be CV_8UC1");
}

// I >= t for integer I is I >= ceil(t); clamped to what a byte can hold.
int IntegerThreshold(double t) {
  if (!(t > 0.0)) return 0;  // also NaN: everything is plant
  if (t > 255.0) return 256;
  return static_cast<int>(std::ceil(t));
}

// Written so that GCC vectorises it (this file is compiled with -O3).
void ThresholdRow(const uint8_t* in, uint8_t* out, int width, int t) {
  if (t <= 0) {
    for (int u = 0; u < width; ++u) out[u] = 255;
    return;
  }
  if (t > 255) {
    for (int u = 0; u < width; ++u) out[u] = 0;
    return;
  }
  const auto level = static_cast<uint8_t>(t);
  for (int u = 0; u < width; ++u) out[u] = in[u] >= level ? 255 : 0;
}

}  // namespace

void FixedThreshold(const cv::Mat& grey, double tau, cv::Mat& mask) {
  CheckGrey(grey);
  // cv::threshold sets pixels strictly above its level: I > ceil(τ) − 1.
  cv::threshold(grey, mask, IntegerThreshold(tau) - 1, 255, cv::THRESH_BINARY);
}

double OtsuThreshold(const cv::Mat& grey, cv::Mat& mask) {
  CheckGrey(grey);
  return cv::threshold(grey, mask, 0, 255, cv::THRESH_BINARY | cv::THRESH_OTSU) + 1.0;
}

double InterpolatedMean::At(int v) const {
  const double centre = v + 0.5, h = height;
  return top + (bottom - top) * (centre - h / 4.0) / (h / 2.0);
}

InterpolatedMean ComputeInterpolatedMean(const cv::Mat& grey) {
  CheckGrey(grey);
  const int half = grey.rows / 2;
  InterpolatedMean m;
  m.height = grey.rows;
  m.top = cv::mean(grey.rowRange(0, std::max(half, 1)))[0];
  m.bottom = cv::mean(grey.rowRange(half, grey.rows))[0];
  return m;
}

void AdaptiveInterpolatingThreshold(const cv::Mat& grey, double alpha, cv::Mat& mask) {
  AdaptiveInterpolatingThreshold(grey, ComputeInterpolatedMean(grey), alpha, mask);
}

void AdaptiveInterpolatingThreshold(const cv::Mat& grey, const InterpolatedMean& mean,
                                    double alpha, cv::Mat& mask) {
  CheckGrey(grey);
  mask.create(grey.size(), CV_8UC1);
  for (int v = 0; v < grey.rows; ++v) {
    ThresholdRow(grey.ptr<uint8_t>(v), mask.ptr<uint8_t>(v), grey.cols,
                 IntegerThreshold(alpha * mean.At(v)));
  }
}

void AdaptiveScore(const cv::Mat& grey, const InterpolatedMean& mean, cv::Mat& score) {
  CheckGrey(grey);
  score.create(grey.size(), CV_32FC1);
  for (int v = 0; v < grey.rows; ++v) {
    const auto inv = static_cast<float>(1.0 / std::max(mean.At(v), 1e-3));
    const auto* in = grey.ptr<uint8_t>(v);
    auto* out = score.ptr<float>(v);
    for (int u = 0; u < grey.cols; ++u) out[u] = static_cast<float>(in[u]) * inv;
  }
}

}  // namespace plantscale::vision
