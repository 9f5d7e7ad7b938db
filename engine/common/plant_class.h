#pragma once
// Soil, crop or weed: what a pixel of a label or a learned model's class map
// is (vision::PixelClass), what a simulated plant is (sim::PlantClass) and
// what a cell of the treatment map holds (treatment::CellClass), one type
// under those three names. The values are the label images' ids (0 soil,
// 1 crop, 2 weed). Formats with an "unknown" keep their own values and
// convert in one place each: the LCM wire's telemetry::PlantKind (unknown 0)
// and the map files' maps::CellClass and maps::PlantKind (unknown 3).

#include <cstdint>

namespace plantscale {

enum class SoilCropWeed : uint8_t { kSoil = 0, kCrop = 1, kWeed = 2 };

// "soil", "crop" or "weed" ("?" for a value out of range).
constexpr const char* ToString(SoilCropWeed c) {
  switch (c) {
    case SoilCropWeed::kSoil: return "soil";
    case SoilCropWeed::kCrop: return "crop";
    case SoilCropWeed::kWeed: return "weed";
  }
  return "?";
}

}  // namespace plantscale
