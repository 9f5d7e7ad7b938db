#include "engine/vision/pixel_classes.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cstdint>

#include "engine/common/options.h"

namespace plantscale::vision {

namespace {

// City-block distance of every pixel to the nearest pixel of class `a` and
// of class `b` (CV_16UC1), by the two-pass four-neighbour sweep (exact for
// L1; Rosenfeld and Pfaltz 1966), both classes in the same sweeps. About a
// sixth of two cv::distanceTransform calls at 640×480.
void L1Distances(const cv::Mat& classes, uint8_t a, uint8_t b, cv::Mat& to_a, cv::Mat& to_b) {
  constexpr int kFar = 0xFFFF;
  const int rows = classes.rows, cols = classes.cols;
  to_a.create(classes.size(), CV_16UC1);
  to_b.create(classes.size(), CV_16UC1);
  for (int y = 0; y < rows; ++y) {
    const uint8_t* c = classes.ptr<uint8_t>(y);
    uint16_t* da = to_a.ptr<uint16_t>(y);
    uint16_t* db = to_b.ptr<uint16_t>(y);
    const uint16_t* ua = y > 0 ? to_a.ptr<uint16_t>(y - 1) : nullptr;
    const uint16_t* ub = y > 0 ? to_b.ptr<uint16_t>(y - 1) : nullptr;
    int la = kFar, lb = kFar;  // the left neighbour's, plus one
    for (int x = 0; x < cols; ++x) {
      int va = c[x] == a ? 0 : std::min(la, kFar);
      int vb = c[x] == b ? 0 : std::min(lb, kFar);
      if (ua) {
        va = std::min(va, ua[x] + 1);
        vb = std::min(vb, ub[x] + 1);
      }
      da[x] = static_cast<uint16_t>(va);
      db[x] = static_cast<uint16_t>(vb);
      la = va + 1;
      lb = vb + 1;
    }
  }
  for (int y = rows - 1; y >= 0; --y) {
    uint16_t* da = to_a.ptr<uint16_t>(y);
    uint16_t* db = to_b.ptr<uint16_t>(y);
    const uint16_t* wa = y + 1 < rows ? to_a.ptr<uint16_t>(y + 1) : nullptr;
    const uint16_t* wb = y + 1 < rows ? to_b.ptr<uint16_t>(y + 1) : nullptr;
    int ra = kFar, rb = kFar;  // the right neighbour's, plus one
    for (int x = cols - 1; x >= 0; --x) {
      int va = std::min<int>(da[x], ra);
      int vb = std::min<int>(db[x], rb);
      if (wa) {
        va = std::min(va, wa[x] + 1);
        vb = std::min(vb, wb[x] + 1);
      }
      da[x] = static_cast<uint16_t>(va);
      db[x] = static_cast<uint16_t>(vb);
      ra = va + 1;
      rb = vb + 1;
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
  L1Distances(classes, static_cast<uint8_t>(PixelClass::kCrop), static_cast<uint8_t>(PixelClass::kWeed), to_crop,
              to_weed);
  cv::Mat crop_side;
  cv::compare(to_crop, to_weed, crop_side, cv::CMP_LE);  // crop pixels: 0 ≤ d_weed
  cv::Mat near_crop;
  cv::dilate(crop_side, near_crop, cv::getStructuringElement(cv::MORPH_RECT, {3, 3}));
  cv::bitwise_and(near_crop, ~crop_side, cut);
}

}  // namespace plantscale::vision
