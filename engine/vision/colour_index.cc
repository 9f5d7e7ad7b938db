#include "engine/vision/colour_index.h"

#include <algorithm>

#include "engine/common/check.h"
#include "engine/common/vectorise.h"

namespace plantscale::vision {
namespace {

// Rounded and clamped to 0..255 (through int, which vectorises).
uint8_t ToByte(float x) {
  return static_cast<uint8_t>(static_cast<int>(std::min(std::max(x, 0.0f), 255.0f) + 0.5f));
}

// Chromatic excess green and excess green minus excess red, scaled to bytes.
// Branch-free so that GCC vectorises it: a black pixel (sum 0) divides by 1
// and is then replaced by 127 (≈ index 0: no evidence either way).
template <ColourIndex kIndex>
PLANTSCALE_VECTOR_CLONES void ChromaticRow(const uint8_t* __restrict bgr,
                                           uint8_t* __restrict out, int width) {
  for (int u = 0; u < width; ++u) {
    const float b = bgr[3 * u], g = bgr[3 * u + 1], r = bgr[3 * u + 2];
    const float sum = r + g + b;
    const float inv = 1.0f / std::max(sum, 1.0f);
    const float exg = (2.0f * g - r - b) * inv;
    uint8_t value;
    if constexpr (kIndex == ColourIndex::kExG) {
      value = ToByte(127.5f + 127.5f * exg);
    } else {
      const float exr = (1.4f * r - g) * inv;
      value = ToByte(127.5f + 85.0f * (exg - exr));
    }
    out[u] = sum > 0.0f ? value : uint8_t{127};
  }
}

PLANTSCALE_VECTOR_CLONES
void CiveRow(const uint8_t* __restrict bgr, uint8_t* __restrict out, int width) {
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
    const auto* in = bgr.ptr<uint8_t>(v);
    auto* o = out.ptr<uint8_t>(v);
    switch (index) {
      case ColourIndex::kExG: ChromaticRow<ColourIndex::kExG>(in, o, bgr.cols); break;
      case ColourIndex::kExGR: ChromaticRow<ColourIndex::kExGR>(in, o, bgr.cols); break;
      case ColourIndex::kCIVE: CiveRow(in, o, bgr.cols); break;
    }
  }
}

}  // namespace plantscale::vision
