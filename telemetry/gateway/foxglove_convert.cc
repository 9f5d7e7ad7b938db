#include "telemetry/gateway/foxglove_convert.h"

#include <openssl/evp.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <string_view>

#include "engine/common/options.h"
#include "engine/geometry/grid_model.h"
#include "telemetry/channels.h"
#include "telemetry/codec.h"
#include "telemetry/convert.h"
#include "telemetry/gateway/foxglove_schemas.h"

namespace plantscale::telemetry::gateway {

namespace {

using nlohmann::json;
namespace ch = channels;

std::vector<Topic> MakeTopics() {
  const auto T = [](std::string name, std::string channel, json schema, TopicClass c) {
    Topic t;
    t.name = std::move(name);
    t.lcm_channel = std::move(channel);
    t.schema_name = schema.at("title").get<std::string>();
    t.schema = std::move(schema);
    t.drop_class = c;
    return t;
  };
  const std::string grid_scene = std::string(ch::kGrid) + "/scene";
  return {
      T(ch::kGrid, ch::kGrid, schemas::GridState(), TopicClass::kGrid),
      T(grid_scene, ch::kGrid, schemas::SceneUpdate(), TopicClass::kGrid),
      T(ch::kPlants, ch::kPlants, schemas::SceneUpdate(), TopicClass::kEssential),
      T(ch::kMapTiles, ch::kMapTiles, schemas::Grid(), TopicClass::kEssential),
      T(ch::kThumbnail, ch::kThumbnail, schemas::CompressedImage(), TopicClass::kThumbnail),
      T(ch::kEvents, ch::kEvents, schemas::Log(), TopicClass::kEssential),
      T(ch::kGatewayEvents, ch::kGatewayEvents, schemas::Log(), TopicClass::kEssential),
      T(ch::kHealth, ch::kHealth, schemas::Health(), TopicClass::kEssential),
      T(ch::kNozzles, ch::kNozzles, schemas::Nozzles(), TopicClass::kDetail),
      T(ch::kOdometry, ch::kOdometry, schemas::Odometry(), TopicClass::kDetail),
      T(ch::kPose, ch::kPose, schemas::Pose(), TopicClass::kDetail),
      T(ch::kSimTruth, ch::kSimTruth, schemas::GridState(), TopicClass::kDetail),
      T(ch::kSimTruthPose, ch::kSimTruthPose, schemas::Pose(), TopicClass::kDetail),
      T(ch::kCommand, ch::kCommand, schemas::Command(), TopicClass::kEssential),
  };
}

json Vec3(double x, double y, double z = 0.0) { return {{"x", x}, {"y", y}, {"z", z}}; }
// Scene geometry to 0.1 mm: nlohmann writes the shortest digits that read
// back, so 0.0123 instead of 0.012345678901234567 (a plant list's JSON is
// a third the size; no drawing shows 0.1 mm).
double Mm10(double v) { return std::round(v * 1e4) / 1e4; }
json Point(double x, double y, double z = 0.0) { return Vec3(Mm10(x), Mm10(y), Mm10(z)); }
json IdentityPose(double x = 0.0, double y = 0.0) {
  return {{"position", Vec3(x, y)},
          {"orientation", {{"x", 0.0}, {"y", 0.0}, {"z", 0.0}, {"w", 1.0}}}};
}
json Rgba(double r, double g, double b, double a) {
  return {{"r", r}, {"g", g}, {"b", b}, {"a", a}};
}

json Entity(const json& stamp, std::string frame, std::string id) {
  return {{"timestamp", stamp},       {"frame_id", std::move(frame)},
          {"id", std::move(id)},      {"lifetime", {{"sec", 0}, {"nsec", 0}}},
          {"frame_locked", false},    {"metadata", json::array()},
          {"arrows", json::array()},  {"cubes", json::array()},
          {"spheres", json::array()}, {"cylinders", json::array()},
          {"lines", json::array()},   {"triangles", json::array()},
          {"texts", json::array()},   {"models", json::array()}};
}

json LinePrimitive(int type, json points, const json& color, double thickness_m) {
  return {{"type", type},
          {"pose", IdentityPose()},
          {"thickness", thickness_m},
          {"scale_invariant", false},
          {"points", std::move(points)},
          {"color", color},
          {"colors", json::array()},
          {"indices", json::array()}};
}

json Sphere(double x, double y, double diameter_m, const json& color) {
  diameter_m = Mm10(diameter_m);
  return {{"pose", IdentityPose(Mm10(x), Mm10(y))},
          {"size", Vec3(diameter_m, diameter_m, 0.005)},
          {"color", color}};
}

const char* ModeName(int8_t mode) {
  switch (mode) {
    case plantscale_grid_state_t::MODE_INITIALISING:
      return "initialising";
    case plantscale_grid_state_t::MODE_TRACKING:
      return "tracking";
    case plantscale_grid_state_t::MODE_DEAD_RECKONING:
      return "dead_reckoning";
    case plantscale_grid_state_t::MODE_LOST:
      return "lost";
    case plantscale_grid_state_t::MODE_TRUTH:
      return "truth";
    default:
      return "unknown";
  }
}

double Sd(double variance) { return std::sqrt(std::max(variance, 0.0)); }

template <typename Message, typename ToJson>
void Add(std::vector<Converted>& out, int topic, const Message& m, ToJson&& to_json) {
  // Strings from the vehicle may hold bytes that are not UTF-8: replaced, not thrown on.
  out.push_back(
      {topic, m.utime, to_json(m).dump(-1, ' ', false, json::error_handler_t::replace), {}});
}

int64_t Int64Field(const json& j, const char* key) {
  if (!j.contains(key)) throw DataError(std::string("plantscale.Command: missing ") + key);
  const json& v = j.at(key);
  if (v.is_number_integer()) return v.get<int64_t>();
  if (v.is_string()) {
    const std::string s = v.get<std::string>();
    size_t used = 0;
    try {
      const int64_t x = std::stoll(s, &used);
      if (used == s.size() && !s.empty()) return x;
    } catch (const std::exception&) {
    }
  }
  throw DataError(std::string("plantscale.Command: ") + key +
                  " must be an integer or a decimal string");
}

int8_t Int8Field(const json& j, const char* key) {
  if (!j.contains(key) || !j.at(key).is_number_integer()) {
    throw DataError(std::string("plantscale.Command: ") + key + " must be an integer");
  }
  const int64_t v = j.at(key).get<int64_t>();
  if (v < -128 || v > 127) {
    throw DataError(std::string("plantscale.Command: ") + key + " out of range (got " +
                    std::to_string(v) + ")");
  }
  return static_cast<int8_t>(v);
}

std::string StringField(const json& j, const char* key) {
  if (!j.contains(key) || !j.at(key).is_string()) {
    throw DataError(std::string("plantscale.Command: ") + key + " must be a string");
  }
  return j.at(key).get<std::string>();
}

int HexDigit(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

}  // namespace

const std::vector<Topic>& Topics() {
  static const std::vector<Topic> topics = MakeTopics();
  return topics;
}

int TopicIndex(const std::string& name) {
  const auto& t = Topics();
  for (size_t i = 0; i < t.size(); ++i) {
    if (t[i].name == name) return static_cast<int>(i);
  }
  return -1;
}

json Timestamp(int64_t utime) {
  const int64_t u = std::max<int64_t>(utime, 0);
  return {{"sec", u / 1'000'000}, {"nsec", (u % 1'000'000) * 1000}};
}

std::string Base64(const uint8_t* data, size_t size) {
  std::string out(4 * ((size + 2) / 3), '\0');
  if (size == 0) return out;
  const int n =
      EVP_EncodeBlock(reinterpret_cast<unsigned char*>(out.data()), data, static_cast<int>(size));
  out.resize(static_cast<size_t>(n));
  return out;
}

json GridStateJson(const plantscale_grid_state_t& m) {
  const GridEstimate e = FromLcm(m);  // DataError on NaN, bad sizes
  return {{"timestamp", Timestamp(m.utime)},
          {"seq", m.seq},
          {"frame_index", m.frame_index},
          {"mode", ModeName(m.filter_mode)},
          {"offset_m", e.state.offset_m},
          {"forward_m", e.state.forward_m},
          {"bearing_rad", e.state.bearing_rad},
          {"bearing_deg", e.state.bearing_rad * 180.0 / std::numbers::pi},
          {"row_spacing_m", e.state.row_spacing_m},
          {"plant_spacing_m", e.state.plant_spacing_m},
          {"offset_sd_m", Sd(e.covariance(0, 0))},
          {"forward_sd_m", Sd(e.covariance(1, 1))},
          {"bearing_sd_rad", Sd(e.covariance(2, 2))},
          {"lines_in_view", e.lines_in_view},
          {"observations", m.observations},
          {"validated", m.validated},
          {"innovation_nis", m.innovation_nis},
          {"innovation_rms_px", m.innovation_rms_px}};
}

json GridSceneJson(const plantscale_grid_state_t& m, int rows_each_side) {
  const GridEstimate e = FromLcm(m);
  int m_lo = 0;
  int m_hi = 4;
  if (!e.lines_in_view.empty()) {
    m_lo = *std::min_element(e.lines_in_view.begin(), e.lines_in_view.end());
    m_hi = *std::max_element(e.lines_in_view.begin(), e.lines_in_view.end());
  }
  const json stamp = Timestamp(m.utime);
  json entity = Entity(stamp, "vehicle", "grid");
  const json row_colour = Rgba(1.0, 0.85, 0.1, 0.9);
  const json plant_colour = Rgba(1.0, 0.85, 0.1, 0.6);
  const double half_line = 0.5 * e.state.plant_spacing_m;
  for (int n = -rows_each_side; n <= rows_each_side; ++n) {
    // The row from half a plant spacing before the first line to half after
    // the last (grid_model.h: plant (m, n) in the vehicle frame).
    const Eigen::Vector2d a = geometry::PlantInVehicle(e.state, m_lo, n);
    const Eigen::Vector2d b = geometry::PlantInVehicle(e.state, m_hi, n);
    const Eigen::Vector2d along = geometry::PlantInVehicle(e.state, m_lo + 1, n) - a;
    const Eigen::Vector2d u = along.normalized() * half_line;
    json points =
        json::array({Point(a.x() - u.x(), a.y() - u.y()), Point(b.x() + u.x(), b.y() + u.y())});
    entity["lines"].push_back(LinePrimitive(0, std::move(points), row_colour, 0.01));
    for (int line = m_lo; line <= m_hi; ++line) {
      const Eigen::Vector2d p = geometry::PlantInVehicle(e.state, line, n);
      entity["spheres"].push_back(Sphere(p.x(), p.y(), 0.04, plant_colour));
    }
  }
  entity["metadata"].push_back({{"key", "mode"}, {"value", ModeName(m.filter_mode)}});
  return {{"deletions", json::array()}, {"entities", json::array({std::move(entity)})}};
}

json PlantsSceneJson(const plantscale_plant_list_t& m) {
  const json stamp = Timestamp(m.utime);
  json entities = json::array();
  for (const plantscale_plant_t& lcm_plant : m.plants) {
    const PlantObservation p = FromLcm(lcm_plant);  // DataError on NaN
    json entity = Entity(stamp, "field", "plant/" + std::to_string(p.id));
    json colour = Rgba(0.6, 0.6, 0.6, 0.8);
    const char* cls = "unknown";
    if (p.kind == PlantKind::kCrop) {
      colour = Rgba(0.1, 0.75, 0.2, 0.8);
      cls = "crop";
    } else if (p.kind == PlantKind::kWeed) {
      colour = Rgba(0.9, 0.15, 0.1, 0.8);
      cls = "weed";
    }
    const double diameter =
        std::max(0.01, 2.0 * std::sqrt(std::max(p.size_m2, 0.0) / std::numbers::pi));
    entity["spheres"].push_back(Sphere(p.position_m.x(), p.position_m.y(), diameter, colour));
    // 95 % ellipse: centre + sqrt(chi2 λi) ei (cos t, sin t).
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(
        0.5 * (p.covariance + p.covariance.transpose()));
    const Eigen::Vector2d lambda = eig.eigenvalues().cwiseMax(0.0);
    const Eigen::Matrix2d axes =
        eig.eigenvectors() * (kChi2_95_2d * lambda).cwiseSqrt().asDiagonal();
    json points = json::array();
    constexpr int kPoints = 24;
    for (int i = 0; i < kPoints; ++i) {
      const double t = 2.0 * std::numbers::pi * i / kPoints;
      const Eigen::Vector2d q = p.position_m + axes * Eigen::Vector2d(std::cos(t), std::sin(t));
      points.push_back(Point(q.x(), q.y(), 0.002));
    }
    const json ellipse_colour = p.sprayed ? Rgba(0.1, 0.4, 1.0, 1.0) : Rgba(1.0, 1.0, 1.0, 0.9);
    entity["lines"].push_back(LinePrimitive(1, std::move(points), ellipse_colour, 0.003));
    entity["metadata"] = json::array({{{"key", "class"}, {"value", cls}},
                                      {{"key", "sprayed"}, {"value", p.sprayed ? "yes" : "no"}},
                                      {{"key", "why"}, {"value", std::to_string(p.why)}}});
    entities.push_back(std::move(entity));
  }
  return {{"deletions", json::array()}, {"entities", std::move(entities)}};
}

json MapTileGridJson(const plantscale_map_tile_t& m) {
  const MapTileDelta tile = FromLcm(m);  // DataError on bad cells
  return {{"timestamp", Timestamp(m.utime)},
          {"frame_id", "field"},
          {"pose", IdentityPose(tile.origin_m.x(), tile.origin_m.y())},
          {"column_count", tile.width},
          {"cell_size", {{"x", tile.resolution_m}, {"y", tile.resolution_m}}},
          {"row_stride", tile.width},
          {"cell_stride", 1},
          {"fields", json::array({{{"name", "cell"}, {"offset", 0}, {"type", 1}}})},
          {"data", Base64(tile.cells.data(), tile.cells.size())}};
}

json ThumbnailJson(const plantscale_thumbnail_t& m) {
  return {{"timestamp", Timestamp(m.utime)},
          {"frame_id", "camera"},
          {"data", Base64(m.jpeg.data(), m.jpeg.size())},
          {"format", "jpeg"}};
}

json EventLogJson(const plantscale_event_t& m) {
  int level = 2;  // INFO
  if (m.severity == plantscale_event_t::SEVERITY_WARNING) level = 3;
  if (m.severity >= plantscale_event_t::SEVERITY_ERROR) level = 4;
  return {{"timestamp", Timestamp(m.utime)},
          {"level", level},
          {"message", m.text},
          {"name", m.kind},
          {"file", ""},
          {"line", 0}};
}

json HealthJson(const plantscale_health_t& m) {
  const Health h = FromLcm(m);
  return {{"timestamp", Timestamp(m.utime)},
          {"seq", m.seq},
          {"protocol_version", m.protocol_version},
          {"source", h.source},
          {"boot_utime", h.boot_utime},
          {"frame_rate_hz", h.frame_rate_hz},
          {"frames", h.frames},
          {"dropped_frames", h.dropped_frames},
          {"distance_m", h.distance_m},
          {"failsafe", h.failsafe},
          {"faults", h.faults},
          {"telemetry_dropped", h.telemetry_dropped}};
}

json NozzlesJson(const plantscale_nozzles_t& m) {
  const NozzleBar bar = FromLcm(m);
  json open = json::array();
  int open_count = 0;
  for (const bool o : bar.open) {
    open.push_back(o);
    open_count += o ? 1 : 0;
  }
  json shots = json::array();
  for (const NozzleShot& s : bar.shots) {
    shots.push_back({{"nozzle", s.nozzle},
                     {"open_utime", s.open_utime},
                     {"close_utime", s.close_utime},
                     {"x_m", s.position_m.x()},
                     {"y_m", s.position_m.y()},
                     {"plant_id", s.plant_id}});
  }
  return {{"timestamp", Timestamp(m.utime)}, {"seq", m.seq},
          {"open", std::move(open)},         {"fault", bar.fault},
          {"open_count", open_count},        {"failsafe", bar.failsafe},
          {"shots", std::move(shots)}};
}

json OdometryJson(const plantscale_odometry_t& m) {
  if (!std::isfinite(m.left_m_s) || !std::isfinite(m.right_m_s) || !std::isfinite(m.distance_m)) {
    throw DataError("plantscale_odometry_t: non-finite speed or distance");
  }
  return {{"timestamp", Timestamp(m.utime)}, {"seq", m.seq},
          {"left_m_s", m.left_m_s},          {"right_m_s", m.right_m_s},
          {"distance_m", m.distance_m},      {"valid", m.valid != 0}};
}

json PoseJson(const plantscale_pose_t& m) {
  const Pose p = FromLcm(m);
  return {{"timestamp", Timestamp(m.utime)},
          {"seq", m.seq},
          {"x_m", p.x_m},
          {"y_m", p.y_m},
          {"heading_rad", p.heading_rad},
          {"heading_deg", p.heading_rad * 180.0 / std::numbers::pi},
          {"x_sd_m", Sd(p.covariance(0, 0))},
          {"y_sd_m", Sd(p.covariance(1, 1))},
          {"heading_sd_rad", Sd(p.covariance(2, 2))}};
}

json CommandJson(const plantscale_command_t& m) {
  static constexpr char kHex[] = "0123456789abcdef";
  std::string mac;
  for (const uint8_t b : m.mac) {
    mac += kHex[b >> 4];
    mac += kHex[b & 15];
  }
  return {{"utime", m.utime}, {"seq", m.seq},       {"command", m.command},
          {"mode", m.mode},   {"origin", m.origin}, {"mac", mac}};
}

plantscale_command_t CommandFromJson(const json& j) {
  if (!j.is_object()) throw DataError("plantscale.Command: not a JSON object");
  plantscale_command_t c;
  c.utime = Int64Field(j, "utime");
  c.seq = Int64Field(j, "seq");
  c.command = Int8Field(j, "command");
  c.mode = Int8Field(j, "mode");
  c.origin = StringField(j, "origin");
  const std::string mac = StringField(j, "mac");
  if (!mac.empty() && mac.size() != 2 * plantscale_command_t::MAC_SIZE) {
    throw DataError("plantscale.Command: mac must be 64 hex digits or empty (got " +
                    std::to_string(mac.size()) + " characters)");
  }
  for (size_t i = 0; i < mac.size(); i += 2) {
    const int hi = HexDigit(mac[i]);
    const int lo = HexDigit(mac[i + 1]);
    if (hi < 0 || lo < 0) throw DataError("plantscale.Command: mac is not hex");
    c.mac.push_back(static_cast<uint8_t>(hi * 16 + lo));
  }
  c.mac_size = static_cast<int16_t>(c.mac.size());
  return c;
}

std::vector<Converted> ConvertLcm(const std::string& channel, const void* data, size_t size,
                                  std::string* error) {
  std::vector<Converted> out;
  std::string decode_error;
  const auto each = [&]<typename Message>(const auto& fill) {
    const auto m = Decode<Message>(channel, data, size, &decode_error);
    if (!m) return;
    fill(*m);
  };
  try {
    const auto topic = [&](const std::string& name) { return TopicIndex(name); };
    if (channel == ch::kGrid) {
      each.operator()<plantscale_grid_state_t>([&](const plantscale_grid_state_t& m) {
        Add(out, topic(ch::kGrid), m, GridStateJson);
        Add(out, topic(std::string(ch::kGrid) + "/scene"), m,
            [](const auto& x) { return GridSceneJson(x); });
      });
    } else if (channel == ch::kSimTruth) {
      each.operator()<plantscale_grid_state_t>(
          [&](const auto& m) { Add(out, topic(ch::kSimTruth), m, GridStateJson); });
    } else if (channel == ch::kPlants) {
      each.operator()<plantscale_plant_list_t>(
          [&](const auto& m) { Add(out, topic(ch::kPlants), m, PlantsSceneJson); });
    } else if (channel == ch::kMapTiles) {
      each.operator()<plantscale_map_tile_t>([&](const auto& m) {
        Add(out, topic(ch::kMapTiles), m, MapTileGridJson);
        out.back().cache_key = std::to_string(m.tile_x) + "," + std::to_string(m.tile_y);
      });
    } else if (channel == ch::kThumbnail) {
      each.operator()<plantscale_thumbnail_t>(
          [&](const auto& m) { Add(out, topic(ch::kThumbnail), m, ThumbnailJson); });
    } else if (channel == ch::kEvents || channel == ch::kGatewayEvents) {
      each.operator()<plantscale_event_t>(
          [&](const auto& m) { Add(out, topic(channel), m, EventLogJson); });
    } else if (channel == ch::kHealth) {
      each.operator()<plantscale_health_t>(
          [&](const auto& m) { Add(out, topic(ch::kHealth), m, HealthJson); });
    } else if (channel == ch::kNozzles) {
      each.operator()<plantscale_nozzles_t>(
          [&](const auto& m) { Add(out, topic(ch::kNozzles), m, NozzlesJson); });
    } else if (channel == ch::kOdometry) {
      each.operator()<plantscale_odometry_t>(
          [&](const auto& m) { Add(out, topic(ch::kOdometry), m, OdometryJson); });
    } else if (channel == ch::kPose || channel == ch::kSimTruthPose) {
      each.operator()<plantscale_pose_t>(
          [&](const auto& m) { Add(out, topic(channel), m, PoseJson); });
    } else if (channel == ch::kCommand) {
      each.operator()<plantscale_command_t>(
          [&](const auto& m) { Add(out, topic(ch::kCommand), m, CommandJson); });
    }
  } catch (const DataError& e) {
    out.clear();
    decode_error = "channel " + channel + ": " + e.what();
  }
  if (!decode_error.empty() && error) *error = decode_error;
  return out;
}

}  // namespace plantscale::telemetry::gateway
