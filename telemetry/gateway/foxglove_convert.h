#pragma once
// The vehicle's LCM messages as the JSON the gateway serves (no networking
// here): every topic, its LCM channel, schema and drop class, and one
// conversion per message type. Foxglove's well-known types where one fits
// (foxglove_schemas.h): the thumbnail as foxglove.CompressedImage, plants
// with their 95 % position ellipses and the grid's rows as
// foxglove.SceneUpdate, map tiles as foxglove.Grid, events as foxglove.Log;
// the rest as flat objects of plottable numbers.
//
// Frames: "field" (plants, map tiles: the field frame of the LCM types),
// "vehicle" (the grid's rows: x right of the camera, y forward; grid_model.h),
// "camera" (the thumbnail).

#include <cstdint>
#include <nlohmann/json.hpp>
#include <plantscale_lcmtypes/plantscale_command_t.hpp>
#include <plantscale_lcmtypes/plantscale_event_t.hpp>
#include <plantscale_lcmtypes/plantscale_grid_state_t.hpp>
#include <plantscale_lcmtypes/plantscale_health_t.hpp>
#include <plantscale_lcmtypes/plantscale_map_tile_t.hpp>
#include <plantscale_lcmtypes/plantscale_nozzles_t.hpp>
#include <plantscale_lcmtypes/plantscale_odometry_t.hpp>
#include <plantscale_lcmtypes/plantscale_plant_list_t.hpp>
#include <plantscale_lcmtypes/plantscale_pose_t.hpp>
#include <plantscale_lcmtypes/plantscale_thumbnail_t.hpp>
#include <string>
#include <vector>

namespace plantscale::telemetry::gateway {

// What a client's queue may drop under back-pressure, first to last
// (client_queue.h): thumbnails, then trace detail; the grid state only
// beyond 2 Hz; essential never.
enum class TopicClass { kThumbnail, kDetail, kGrid, kEssential };

struct Topic {
  std::string name;         // the Foxglove topic
  std::string lcm_channel;  // where it comes from
  std::string schema_name;
  nlohmann::json schema;
  TopicClass drop_class = TopicClass::kEssential;
};

// Every topic served, in a fixed order: the advertised channel id of
// Topics()[i] is i + 1.
const std::vector<Topic>& Topics();
// Index into Topics() of `name`, or -1.
int TopicIndex(const std::string& name);

// The 95 % ellipse of a 2-D normal (chi-square, 2 degrees of freedom).
inline constexpr double kChi2_95_2d = 5.991464547107979;

// foxglove time from LCM microseconds.
nlohmann::json Timestamp(int64_t utime);
// RFC 4648 base64 (what foxglove's JSON encoding expects for bytes).
std::string Base64(const uint8_t* data, size_t size);

// Conversions; those of types with FromLcm checks (convert.h) throw
// DataError for what they reject (NaN, wrong sizes, bad run-length cells).
nlohmann::json GridStateJson(const plantscale_grid_state_t& m);
// The grid's rows −rows_each_side..rows_each_side between the first and last
// plant line in view (lines 0–4 when none), and its plants on them, in the
// vehicle frame.
nlohmann::json GridSceneJson(const plantscale_grid_state_t& m, int rows_each_side = 1);
// One entity per plant ("plant/ID"): a disc of its ground area coloured by
// class (crop green, weed red, unknown grey; sprayed: blue outline) and its
// 95 % position ellipse as a line loop of 24 points; scene geometry is
// rounded to 0.1 mm.
nlohmann::json PlantsSceneJson(const plantscale_plant_list_t& m);
// Cells decoded (RLE) into one UINT8 field "cell" (CELL_* values).
nlohmann::json MapTileGridJson(const plantscale_map_tile_t& m);
nlohmann::json ThumbnailJson(const plantscale_thumbnail_t& m);
nlohmann::json EventLogJson(const plantscale_event_t& m);
nlohmann::json HealthJson(const plantscale_health_t& m);
nlohmann::json NozzlesJson(const plantscale_nozzles_t& m);
nlohmann::json OdometryJson(const plantscale_odometry_t& m);
nlohmann::json PoseJson(const plantscale_pose_t& m);
nlohmann::json CommandJson(const plantscale_command_t& m);
// What an operator's client publishes on PLANTSCALE_COMMAND (schema
// plantscale.Command) back into the LCM message, field for field, so that
// the station's signature over it still verifies. Throws DataError naming
// the field for a missing or mistyped field, an int8 out of range or a mac
// that is not 64 hex digits (or empty: unsigned).
plantscale_command_t CommandFromJson(const nlohmann::json& j);

struct Converted {
  int topic = -1;  // index into Topics()
  int64_t utime = 0;
  std::string json;
  std::string cache_key;  // map tiles: "x,y" (a new client is sent every tile's newest)
};

// Decodes `size` bytes received on `channel` and converts them for every
// topic fed by that channel (none for a channel the gateway does not
// serve). On bad bytes or rejected values returns nothing and sets `*error`
// to one line naming the channel; never throws.
std::vector<Converted> ConvertLcm(const std::string& channel, const void* data, size_t size,
                                  std::string* error);

}  // namespace plantscale::telemetry::gateway
