#include "engine/vision/pixel_classes.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cstdint>

#include "engine/common/options.h"

namespace plantscale::vision {

namespace {

// City-block distance of every pixel to the nearest pixel of class `value`
// (CV_16UC1), by the two-pass four-neighbour sweep (exact for L1; Rosenfeld
// and Pfaltz 1966): down and right from the upper and left neighbours, then
// up and left from the lower and right ones. Two of them cost about a sixth
// of two cv::distanceTransform calls at 640×480.
void L1Distance(const cv::Mat& classes, uint8_t value, cv::Mat& dist) {
  constexpr int kFar = 0xFFFF;
  const int rows = classes.rows, cols = classes.cols;
  dist.create(classes.size(), CV_16UC1);
  for (int y = 0; y < rows; ++y) {
    const uint8_t* c = classes.ptr<uint8_t>(y);
    uint16_t* d = dist.ptr<uint16_t>(y);
    const uint16_t* up = y > 0 ? dist.ptr<uint16_t>(y - 1) : nullptr;
    int left = kFar;  // the left neighbour's, plus one
    for (int x = 0; x < cols; ++x) {
      int v = c[x] == value ? 0 : std::min(left, kFar);
      if (up) v = std::min(v, up[x] + 1);
      d[x] = static_cast<uint16_t>(v);
      left = v + 1;
    }
  }
  for (int y = rows - 1; y >= 0; --y) {
    uint16_t* d = dist.ptr<uint16_t>(y);
    const uint16_t* down = y + 1 < rows ? dist.ptr<uint16_t>(y + 1) : nullptr;
    int right = kFar;  // the right neighbour's, plus one
    for (int x = cols - 1; x >= 0; --x) {
      int v = std::min<int>(d[x], right);
      if (down) v = std::min(v, down[x] + 1);
      d[x] = static_cast<uint16_t>(v);
      right = v + 1;
    }
  }
}

}  // namespace

void ClassCut(const cv::Mat& classes, cv::Mat& cut) {
  if (classes.empty() || classes.type() != CV_8UC1) throw DataError("classes must be CV_8UC1");
  if (cv::countNonZero(classes == static_cast<int>(PixelClass::kWeed)) == 0 ||
      cv::countNonZero(classes == static_cast<int>(PixelClass::kCrop)) == 0) {
    cut = cv::Mat::zeros(classes.size(), CV_8UC1);
    return;
  }
  // Distance of every pixel to the nearest crop / weed pixel.
  cv::Mat to_crop, to_weed;
  L1Distance(classes, static_cast<uint8_t>(PixelClass::kCrop), to_crop);
  L1Distance(classes, static_cast<uint8_t>(PixelClass::kWeed), to_weed);
  cv::Mat crop_side;
  cv::compare(to_crop, to_weed, crop_side, cv::CMP_LE);  // crop pixels: 0 ≤ d_weed
  cv::Mat near_crop;
  cv::dilate(crop_side, near_crop, cv::getStructuringElement(cv::MORPH_RECT, {3, 3}));
  cv::bitwise_and(near_crop, ~crop_side, cut);
}

}  // namespace plantscale::vision
