#include "engine/vision/pixel_classes.h"

#include <opencv2/imgproc.hpp>

#include "engine/common/options.h"

namespace plantscale::vision {

void ClassCut(const cv::Mat& classes, cv::Mat& cut) {
  if (classes.empty() || classes.type() != CV_8UC1) throw DataError("classes must be CV_8UC1");
  cv::Mat crop, weed;
  cv::compare(classes, static_cast<int>(PixelClass::kCrop), crop, cv::CMP_EQ);
  cv::compare(classes, static_cast<int>(PixelClass::kWeed), weed, cv::CMP_EQ);
  if (cv::countNonZero(weed) == 0 || cv::countNonZero(crop) == 0) {
    cut = cv::Mat::zeros(classes.size(), CV_8UC1);
    return;
  }
  // Distance of every pixel to the nearest crop / weed pixel.
  cv::Mat to_crop, to_weed;
  cv::distanceTransform(~crop, to_crop, cv::DIST_L1, 3, CV_32F);
  cv::distanceTransform(~weed, to_weed, cv::DIST_L1, 3, CV_32F);
  cv::Mat crop_side;
  cv::compare(to_crop, to_weed, crop_side, cv::CMP_LE);  // crop pixels: 0 ≤ d_weed
  cv::Mat near_crop;
  cv::dilate(crop_side, near_crop, cv::getStructuringElement(cv::MORPH_RECT, {3, 3}));
  cv::bitwise_and(near_crop, ~crop_side, cut);
}
}  // namespace plantscale::vision
