#include "telemetry/gateway/foxglove_schemas.h"

#include <initializer_list>
#include <string>
#include <utility>

namespace plantscale::telemetry::gateway::schemas {

namespace {

using nlohmann::json;

json Number() { return {{"type", "number"}}; }
json Integer() { return {{"type", "integer"}}; }
json Integer(int64_t min, int64_t max) {
  return {{"type", "integer"}, {"minimum", min}, {"maximum", max}};
}
json String() { return {{"type", "string"}}; }
json Boolean() { return {{"type", "boolean"}}; }
json Array(json items) { return {{"type", "array"}, {"items", std::move(items)}}; }
json Base64() { return {{"type", "string"}, {"contentEncoding", "base64"}}; }

// An object with exactly these properties, all required (what the gateway
// writes always has every field, so a client may rely on each).
json Object(std::initializer_list<std::pair<const char*, json>> properties,
            const char* title = nullptr) {
  json props = json::object();
  json required = json::array();
  for (const auto& [name, schema] : properties) {
    props[name] = schema;
    required.push_back(name);
  }
  json o = {{"type", "object"},
            {"properties", std::move(props)},
            {"required", std::move(required)},
            {"additionalProperties", false}};
  if (title) o["title"] = title;
  return o;
}

json Time() {
  return Object({{"sec", Integer(0, 4294967295)}, {"nsec", Integer(0, 999999999)}}, "time");
}
json Vector2() { return Object({{"x", Number()}, {"y", Number()}}, "foxglove.Vector2"); }
json Vector3() {
  return Object({{"x", Number()}, {"y", Number()}, {"z", Number()}}, "foxglove.Vector3");
}
json Quaternion() {
  return Object({{"x", Number()}, {"y", Number()}, {"z", Number()}, {"w", Number()}},
                "foxglove.Quaternion");
}
json PoseSchema() {
  return Object({{"position", Vector3()}, {"orientation", Quaternion()}}, "foxglove.Pose");
}
json Color() {
  return Object({{"r", Number()}, {"g", Number()}, {"b", Number()}, {"a", Number()}},
                "foxglove.Color");
}

json Sphere() {
  return Object({{"pose", PoseSchema()}, {"size", Vector3()}, {"color", Color()}},
                "foxglove.SpherePrimitive");
}
json Line() {
  return Object({{"type", Integer(0, 2)},  // LINE_STRIP, LINE_LOOP, LINE_LIST
                 {"pose", PoseSchema()},
                 {"thickness", Number()},
                 {"scale_invariant", Boolean()},
                 {"points", Array(Vector3())},
                 {"color", Color()},
                 {"colors", Array(Color())},
                 {"indices", Array(Integer(0, 4294967295))}},
                "foxglove.LinePrimitive");
}
json Text() {
  return Object({{"pose", PoseSchema()},
                 {"billboard", Boolean()},
                 {"font_size", Number()},
                 {"scale_invariant", Boolean()},
                 {"color", Color()},
                 {"text", String()}},
                "foxglove.TextPrimitive");
}
// Primitive kinds plantscale never sends: always empty arrays.
json EmptyArray() { return {{"type", "array"}, {"items", {{"type", "object"}}}, {"maxItems", 0}}; }

}  // namespace

json CompressedImage() {
  return Object(
      {{"timestamp", Time()}, {"frame_id", String()}, {"data", Base64()}, {"format", String()}},
      "foxglove.CompressedImage");
}

json SceneUpdate() {
  const json deletion = Object({{"timestamp", Time()}, {"type", Integer(0, 1)}, {"id", String()}},
                               "foxglove.SceneEntityDeletion");
  const json duration = Object({{"sec", Integer()}, {"nsec", Integer(0, 999999999)}}, "duration");
  const json entity =
      Object({{"timestamp", Time()},
              {"frame_id", String()},
              {"id", String()},
              {"lifetime", duration},
              {"frame_locked", Boolean()},
              {"metadata",
               Array(Object({{"key", String()}, {"value", String()}}, "foxglove.KeyValuePair"))},
              {"arrows", EmptyArray()},
              {"cubes", EmptyArray()},
              {"spheres", Array(Sphere())},
              {"cylinders", EmptyArray()},
              {"lines", Array(Line())},
              {"triangles", EmptyArray()},
              {"texts", Array(Text())},
              {"models", EmptyArray()}},
             "foxglove.SceneEntity");
  return Object({{"deletions", Array(deletion)}, {"entities", Array(entity)}},
                "foxglove.SceneUpdate");
}

json Grid() {
  const json field =
      Object({{"name", String()}, {"offset", Integer(0, 4294967295)}, {"type", Integer(0, 8)}},
             "foxglove.PackedElementField");
  return Object({{"timestamp", Time()},
                 {"frame_id", String()},
                 {"pose", PoseSchema()},
                 {"column_count", Integer(0, 4294967295)},
                 {"cell_size", Vector2()},
                 {"row_stride", Integer(0, 4294967295)},
                 {"cell_stride", Integer(0, 4294967295)},
                 {"fields", Array(field)},
                 {"data", Base64()}},
                "foxglove.Grid");
}

json Log() {
  return Object({{"timestamp", Time()},
                 {"level", Integer(0, 5)},  // UNKNOWN, DEBUG, INFO, WARNING, ERROR, FATAL
                 {"message", String()},
                 {"name", String()},
                 {"file", String()},
                 {"line", Integer(0, 4294967295)}},
                "foxglove.Log");
}

json GridState() {
  return Object({{"timestamp", Time()},
                 {"seq", Integer()},
                 {"frame_index", Integer()},
                 {"mode", String()},
                 {"offset_m", Number()},
                 {"forward_m", Number()},
                 {"bearing_rad", Number()},
                 {"bearing_deg", Number()},
                 {"row_spacing_m", Number()},
                 {"plant_spacing_m", Number()},
                 {"offset_sd_m", Number()},
                 {"forward_sd_m", Number()},
                 {"bearing_sd_rad", Number()},
                 {"lines_in_view", Array(Integer())},
                 {"observations", Integer()},
                 {"validated", Integer()},
                 {"innovation_nis", Number()},
                 {"innovation_rms_px", Number()}},
                "plantscale.GridState");
}

json Health() {
  return Object({{"timestamp", Time()},
                 {"seq", Integer()},
                 {"protocol_version", Integer()},
                 {"source", String()},
                 {"boot_utime", Integer()},
                 {"frame_rate_hz", Number()},
                 {"frames", Integer()},
                 {"dropped_frames", Integer()},
                 {"distance_m", Number()},
                 {"failsafe", Boolean()},
                 {"faults", Array(String())},
                 {"telemetry_dropped", Integer()}},
                "plantscale.Health");
}

json Nozzles() {
  const json shot = Object({{"nozzle", Integer()},
                            {"open_utime", Integer()},
                            {"close_utime", Integer()},
                            {"x_m", Number()},
                            {"y_m", Number()},
                            {"plant_id", Integer()}},
                           "plantscale.Shot");
  return Object({{"timestamp", Time()},
                 {"seq", Integer()},
                 {"open", Array(Boolean())},
                 {"fault", Array(Integer())},
                 {"open_count", Integer()},
                 {"failsafe", Boolean()},
                 {"shots", Array(shot)}},
                "plantscale.Nozzles");
}

json Odometry() {
  return Object({{"timestamp", Time()},
                 {"seq", Integer()},
                 {"left_m_s", Number()},
                 {"right_m_s", Number()},
                 {"distance_m", Number()},
                 {"valid", Boolean()}},
                "plantscale.Odometry");
}

json Pose() {
  return Object({{"timestamp", Time()},
                 {"seq", Integer()},
                 {"x_m", Number()},
                 {"y_m", Number()},
                 {"heading_rad", Number()},
                 {"heading_deg", Number()},
                 {"x_sd_m", Number()},
                 {"y_sd_m", Number()},
                 {"heading_sd_rad", Number()}},
                "plantscale.Pose");
}

json Command() {
  // What the gateway serves (integers). An operator may send utime and seq
  // as decimal strings too (CommandFromJson), for clients whose numbers are
  // doubles (exact only below 2^53).
  return Object({{"utime", Integer()},
                 {"seq", Integer()},
                 {"command", Integer(-128, 127)},
                 {"mode", Integer(-128, 127)},
                 {"origin", String()},
                 {"mac", String()}},  // 64 hex digits, or empty: unsigned
                "plantscale.Command");
}

}  // namespace plantscale::telemetry::gateway::schemas
