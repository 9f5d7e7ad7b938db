#pragma once
// The motion mosaic (engine/motion/mosaic.h) as a maps::CropMap for export.
// The engine builds its own MosaicMap so that it does not depend on maps/;
// this is where the two meet. Cells keep their labels (plant → crop), the
// mosaic's plants are registered as crops (ids 1, 2, ... in mosaic order;
// CropMap::AddPlant paints their discs as crop over soil and unknown) and
// the metadata names the source and the number of frames.

#include "engine/motion/mosaic.h"
#include "maps/crop_map.h"

namespace plantscale::app {

maps::CropMap ToCropMap(const motion::MosaicMap& mosaic);

}  // namespace plantscale::app
