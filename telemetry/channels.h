#pragma once
// The LCM channels of plantscale and their default publish rates (docs/telemetry.md
// has the same table). Vehicle → station unless marked otherwise.

namespace plantscale::telemetry::channels {

inline constexpr char kGrid[] = "PLANTSCALE_GRID";            // grid_state_t, tracker, 12.5 Hz
inline constexpr char kPlants[] = "PLANTSCALE_PLANTS";        // plant_list_t, 12.5 Hz
inline constexpr char kMapTiles[] = "PLANTSCALE_MAP_TILES";   // map_tile_t, on change
inline constexpr char kNozzles[] = "PLANTSCALE_NOZZLES";      // nozzles_t, 12.5 Hz
inline constexpr char kHealth[] = "PLANTSCALE_HEALTH";        // health_t, 2 Hz heartbeat
inline constexpr char kThumbnail[] = "PLANTSCALE_THUMBNAIL";  // thumbnail_t, 2 Hz
inline constexpr char kEvents[] = "PLANTSCALE_EVENTS";        // event_t, when they happen
inline constexpr char kOdometry[] = "PLANTSCALE_ODOMETRY";    // odometry_t, 12.5 Hz
inline constexpr char kPose[] = "PLANTSCALE_POSE";            // pose_t, dead reckoning
// The gateway's own events (event_t): refused connections and commands.
inline constexpr char kGatewayEvents[] = "PLANTSCALE_GATEWAY_EVENTS";
// Simulator ground truth: never on the tracker's channels.
inline constexpr char kSimTruth[] = "PLANTSCALE_SIM_TRUTH";           // grid_state_t, MODE_TRUTH
inline constexpr char kSimTruthPose[] = "PLANTSCALE_SIM_TRUTH_POSE";  // pose_t
// Station → vehicle, and sensors → vehicle for `plantscale run`.
inline constexpr char kCommand[] = "PLANTSCALE_COMMAND";         // command_t
inline constexpr char kOdometryIn[] = "PLANTSCALE_ODOMETRY_IN";  // odometry_t, 50 Hz

}  // namespace plantscale::telemetry::channels
