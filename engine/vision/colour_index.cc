#include "engine/vision/colour_index.h"

#include <algorithm>

#include "engine/common/check.h"

namespace plantscale::vision {
namespace {

uint8_t ToByte(float x) { return static_cast<uint8_t>(std::clamp(x, 0.0f, 255.0f) + 0.5f); }

// Chromatic excess green and excess green minus excess red, scaled to bytes.
void ChromaticRow(const uint8_t* bgr, uint8_t* out, int width, ColourIndex index) {
  for (int u = 0; u < width; ++u) {
    const float b = bgr[3 * u], g = bgr[3 * u + 1], r = bgr[3 * u + 2];
    const float sum = r + g + b;
    if (sum <= 0.0f) {
      out[u] = 127;  // black: no evidence either way (≈ index 0)
      continue;
    }
    const float inv = 1.0f / sum;
    const float exg = (2.0f * g - r - b) * inv;
    if (index == ColourIndex::kExG) {
      out[u] = ToByte(127.5f + 127.5f * exg);
    } else {
      const float exr = (1.4f * r - g) * inv;
      out[u] = ToByte(127.5f + 85.0f * (exg - exr));
    }
  }
}

void CiveRow(const uint8_t* bgr, uint8_t* out, int width) {
  for (int u = 0; u < width; ++u) {
    const float b = bgr[3 * u], g = bgr[3 * u + 1], r = bgr[3 * u + 2];
    const float cive = 0.441f * r - 0.811f * g + 0.385f * b + 18.78745f;
    out[u] = ToByte(127.5f - cive);
  }
}

}  // namespace

std::optional<ColourIndex> ParseColourIndex(std::string_view name) {
  if (name == "exg") return ColourIndex::kExG;
  if (name == "exgr") return ColourIndex::kExGR;
  if (name == "cive") return ColourIndex::kCIVE;
  return std::nullopt;
}

const char* Name(ColourIndex index) {
  switch (index) {
    case ColourIndex::kExG: return "exg";
    case ColourIndex::kExGR: return "exgr";
    case ColourIndex::kCIVE: return "cive";
  }
  return "?";
}

void ComputeColourIndex(const cv::Mat& bgr, ColourIndex index, cv::Mat& out) {
  PLANTSCALE_CHECK(bgr.type() == CV_8UC3, "colour index input must be CV_8UC3 (BGR)");
  out.create(bgr.size(), CV_8UC1);
  for (int v = 0; v < bgr.rows; ++v) {
    if (index == ColourIndex::kCIVE) {
      CiveRow(bgr.ptr<uint8_t>(v), out.ptr<uint8_t>(v), bgr.cols);
    } else {
      ChromaticRow(bgr.ptr<uint8_t>(v), out.ptr<uint8_t>(v), bgr.cols, index);
    }
  }
}

}  // namespace plantscale::vision
