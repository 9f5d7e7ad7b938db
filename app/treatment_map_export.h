#pragma once
// The treatment chain's map as a maps::CropMap, so every export (GeoTIFF,
// GeoPackage, GeoJSON, CSV, PNG) takes it: the class layer is the treatment
// map's majority decision (cells with no votes are soil), and every plant
// record joins the registry with its class, size, whether it was sprayed
// and why. Positions are in the bed frame (engine/treatment/bed_frame.h).

#include "engine/treatment/treatment_system.h"
#include "maps/crop_map.h"

namespace plantscale::app {

maps::CropMap ToCropMap(const treatment::TreatmentMap& map,
                        const treatment::PlantRegistry& registry);

}  // namespace plantscale::app
