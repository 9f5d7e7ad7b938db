#pragma once
// ToLcm / FromLcm between telemetry value types (types.h, engine types) and
// the generated LCM messages. FromLcm checks what arrives and throws
// DataError naming the type and field (NaN, wrong sizes) rather than passing
// nonsense on. Sequence numbers are set by the caller.

#include <plantscale_lcmtypes/plantscale_grid_state_t.hpp>
#include <plantscale_lcmtypes/plantscale_health_t.hpp>
#include <plantscale_lcmtypes/plantscale_map_tile_t.hpp>
#include <plantscale_lcmtypes/plantscale_nozzles_t.hpp>
#include <plantscale_lcmtypes/plantscale_plant_list_t.hpp>
#include <plantscale_lcmtypes/plantscale_pose_t.hpp>

#include "telemetry/types.h"

namespace plantscale::telemetry {

plantscale_grid_state_t ToLcm(const GridEstimate& estimate);
GridEstimate FromLcm(const plantscale_grid_state_t& message);

// Ground truth of the simulator as a grid message (mode TRUTH, zero covariance).
plantscale_grid_state_t TruthToLcm(const geometry::GridState& truth, int64_t utime,
                                   int frame_index);

plantscale_plant_t ToLcm(const PlantObservation& plant);
PlantObservation FromLcm(const plantscale_plant_t& message);
plantscale_plant_list_t ToLcm(const std::vector<PlantObservation>& plants, int64_t utime,
                              int frame_index);

// Cells are run-length encoded (rle.h).
plantscale_map_tile_t ToLcm(const MapTileDelta& tile, int64_t utime);
MapTileDelta FromLcm(const plantscale_map_tile_t& message);

plantscale_nozzles_t ToLcm(const NozzleBar& bar, int64_t utime);
NozzleBar FromLcm(const plantscale_nozzles_t& message);

plantscale_pose_t ToLcm(const Pose& pose, int64_t utime);
Pose FromLcm(const plantscale_pose_t& message);

plantscale_health_t ToLcm(const Health& health, int64_t utime);
Health FromLcm(const plantscale_health_t& message);

}  // namespace plantscale::telemetry
