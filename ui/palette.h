#pragma once
// Colours of the station and the report. Map classes follow maps/png_writer.cc
// (soil brown, crop green, weed red, treated blue) so a report picture and an
// exported PNG read the same.

#include "ui/canvas.h"

namespace plantscale::ui::palette {

inline constexpr Rgb kBackground{0.08, 0.09, 0.10};
inline constexpr Rgb kUnknownCell{0.16, 0.17, 0.18};
inline constexpr Rgb kSoil{140 / 255.0, 105 / 255.0, 70 / 255.0};
inline constexpr Rgb kCrop{40 / 255.0, 170 / 255.0, 60 / 255.0};
inline constexpr Rgb kWeed{220 / 255.0, 40 / 255.0, 40 / 255.0};
inline constexpr Rgb kTreated{20 / 255.0, 120 / 255.0, 230 / 255.0};
inline constexpr Rgb kUnknownPlant{0.95, 0.85, 0.20};
inline constexpr Rgb kRowLine{1.0, 0.85, 0.0};     // predicted rows
inline constexpr Rgb kPlantLine{0.0, 0.85, 0.95};  // predicted plant lines
inline constexpr Rgb kVehicle{1.0, 0.3, 1.0};      // vehicle marker and its ellipse
inline constexpr Rgb kPath{0.85, 0.85, 0.85};
inline constexpr Rgb kPlantEllipse{1.0, 1.0, 1.0};
inline constexpr Rgb kGate{1.0, 0.55, 0.0};
inline constexpr Rgb kPick{1.0, 0.45, 0.0};  // the picked plant's ring and the measured line
// Blob rings in the camera view: lighter than the plants they ring.
inline constexpr Rgb kBlobCrop{0.55, 1.0, 0.55};
inline constexpr Rgb kBlobWeed{1.0, 0.25, 0.25};
inline constexpr Rgb kBlobUnknown{1.0, 1.0, 0.6};
inline constexpr Rgb kHudOk{0.10, 0.22, 0.14};
inline constexpr Rgb kHudLost{0.80, 0.05, 0.05};
inline constexpr Rgb kHudNoMessages{0.55, 0.40, 0.0};
inline constexpr Rgb kHudFinished{0.14, 0.18, 0.30};  // the run ended: quiet slate
inline constexpr Rgb kNozzleClosed{0.30, 0.30, 0.32};
inline constexpr Rgb kNozzleOpen{0.10, 0.60, 1.0};
inline constexpr Rgb kNozzleFault{1.0, 0.5, 0.0};

}  // namespace plantscale::ui::palette
