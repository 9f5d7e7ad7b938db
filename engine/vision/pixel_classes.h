#pragma once
// Crop, weed and soil per pixel, as a learned model gives them
// (learned_segmenter.h), and the cut that keeps a crop's blob and a weed
// touching it apart (Segmenter::Process with classes).

#include <cstdint>
#include <opencv2/core.hpp>

#include "engine/common/plant_class.h"

namespace plantscale::vision {

// Pixel classes, as in every label image: 0 soil, 1 crop, 2 weed
// (engine/common/plant_class.h).
using PixelClass = SoilCropWeed;
inline constexpr int kPixelClassCount = 3;

struct ClassMaps {
  cv::Mat classes;     // CV_8UC1, the photograph's size: 0 soil, 1 crop, 2 weed
  cv::Mat confidence;  // CV_32FC1, the photograph's size: probability of the class chosen
};

// The pixels a plant mask is cut along so that crop and weed fall into
// separate blobs (CV_8UC1, 255 on the cut, of `classes`' size). Every pixel
// takes a side: crop pixels the crop's, weed pixels the weed's, and soil
// pixels the side of the nearer of the two (L1 distance; the crop's on a
// tie, and every one when the frame holds no weed). The cut is the weed
// side's pixels next to the crop side's (8-neighbours): a crop keeps all of
// its pixels, a weed touching it loses a one-pixel arc, and plant matter the
// model calls soil between them (the threshold's rim, the segmenter's
// growth) is cut where it is as far from either.
void ClassCut(const cv::Mat& classes, cv::Mat& cut);

}  // namespace plantscale::vision
