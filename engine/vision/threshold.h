#pragma once
// Plant-matter thresholds on a single-channel 8-bit image in which plants are
// brighter than soil (near-infrared grey, or a colour index from
// colour_index.h). Plain image in, 255/0 mask out; `mask` is reused when it
// already has the right size and type, so no allocation after the first frame.

#include <opencv2/core.hpp>

namespace plantscale::vision {

// Thesis eq. 2.14: O = 255 where I >= τ.
void FixedThreshold(const cv::Mat& grey, double tau, cv::Mat& mask);

// Otsu's threshold (the between-class-variance maximum); returns the τ used
// in the sense of eq. 2.14 (O = 255 where I >= τ).
double OtsuThreshold(const cv::Mat& grey, cv::Mat& mask);

// Hague's adaptive interpolating threshold (thesis §2.3.4, eq. 2.15): the
// means μ1, μ2 of the top and bottom halves of the image, taken as the mean
// grey levels at the centres of those halves (v = h/4 and 3h/4) and
// interpolated linearly (extrapolated beyond them) down the image:
//   μ(v) = μ1 + (μ2 − μ1)·(v − h/4)/(h/2),   O = 255 where I >= α·μ(v).
struct InterpolatedMean {
  double top = 0.0;     // μ1
  double bottom = 0.0;  // μ2
  int height = 0;
  // μ at the centre of image row v (v + 0.5 in pixel coordinates).
  double At(int v) const;
};
InterpolatedMean ComputeInterpolatedMean(const cv::Mat& grey);
void AdaptiveInterpolatingThreshold(const cv::Mat& grey, double alpha, cv::Mat& mask);
// The same with the means already computed (one pass fewer when sweeping α).
void AdaptiveInterpolatingThreshold(const cv::Mat& grey, const InterpolatedMean& mean,
                                    double alpha, cv::Mat& mask);

// The score the adaptive threshold compares with α: I / μ(v) (CV_32FC1).
void AdaptiveScore(const cv::Mat& grey, const InterpolatedMean& mean, cv::Mat& score);


}  // namespace plantscale::vision
