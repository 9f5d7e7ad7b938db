#pragma once
// Crop-row labels as the CRDA benchmark draws them: white (>= 128) lines on
// black. Shared by `evaluate rows --images` and tools/crda_score.

#include <cstdint>
#include <vector>

namespace plantscale::rows {

// Centres of the white runs of one label row of `cols` bytes, left to right,
// in label pixels times `scale` (u = (start + end) / 2 · scale, end exclusive).
std::vector<double> LabelLineCentres(const uint8_t* row, int cols, double scale = 1.0);

}  // namespace plantscale::rows
