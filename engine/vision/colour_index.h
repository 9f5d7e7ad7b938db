#pragma once
// Colour vegetation indices for RGB cameras: each maps a BGR image (CV_8UC3,
// OpenCV's order) to an 8-bit image in which plants are bright, so that the
// thresholds of threshold.h apply unchanged.
//
//   ExG  = 2g − r − b on chromaticity r = R/(R+G+B), ... (Woebbecke et al.
//          1995); out = 127.5 + 127.5·ExG, clamped.
//   ExGR = ExG − ExR, ExR = 1.4r − g (Meyer & Neto 2008), plant where > 0;
//          out = 127.5 + 85·ExGR, so its natural threshold 0 sits at 127.5.
//   CIVE = 0.441R − 0.811G + 0.385B + 18.78745 (Kataoka et al. 2003), plant
//          where low; out = 127.5 − CIVE, clamped.
// Chromaticity makes ExG and ExGR insensitive to overall brightness (shadow,
// exposure), CIVE is not. Which one we use by default is chosen by
// measurement (see `plantscale evaluate segmentation --image rgb`).

#include <opencv2/core.hpp>
#include <optional>
#include <string_view>

namespace plantscale::vision {

enum class ColourIndex { kExG, kExGR, kCIVE };

std::optional<ColourIndex> ParseColourIndex(std::string_view name);  // "exg", "exgr", "cive"
const char* Name(ColourIndex index);

// `out` is reused when it already has the right size and type.
void ComputeColourIndex(const cv::Mat& bgr, ColourIndex index, cv::Mat& out);

}  // namespace plantscale::vision
