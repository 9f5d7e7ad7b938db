#include "telemetry/gateway/foxglove_convert.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>

#include "engine/common/options.h"
#include "telemetry/channels.h"
#include "telemetry/codec.h"
#include "telemetry/convert.h"

namespace plantscale::telemetry::gateway {
namespace {

using nlohmann::json;

plantscale_grid_state_t SomeGrid() {
  GridEstimate e;
  e.utime = 1'700'000'000'123'456;
  e.frame_index = 42;
  e.state = {0.012, 0.31, -0.02, 0.48, 0.44};
  e.covariance = geometry::Matrix5d::Identity() * 1e-4;
  e.covariance(2, 2) = 2.5e-5;
  e.mode = FilterMode::kTracking;
  e.lines_in_view = {1, 2, 3};
  e.observations = 17;
  e.validated = 15;
  e.innovation_nis = 4.25;
  e.innovation_rms_px = 1.5;
  plantscale_grid_state_t m = ToLcm(e);
  m.seq = 7;
  return m;
}

TEST(GatewayConvert, TimestampSplitsMicrosecondsIntoSecondsAndNanoseconds) {
  const json t = Timestamp(1'700'000'000'123'456);
  EXPECT_EQ(t.at("sec").get<int64_t>(), 1'700'000'000);
  EXPECT_EQ(t.at("nsec").get<int64_t>(), 123'456'000);
}

TEST(GatewayConvert, Base64IsRfc4648) {
  const uint8_t bytes[] = {'f', 'o', 'o', 'b', 'a', 'r'};
  EXPECT_EQ(Base64(bytes, 6), "Zm9vYmFy");
  EXPECT_EQ(Base64(bytes, 5), "Zm9vYmE=");
  EXPECT_EQ(Base64(bytes, 4), "Zm9vYg==");
  EXPECT_EQ(Base64(bytes, 0), "");
}

TEST(GatewayConvert, GridStateIsPlottableNumbersWithStandardDeviations) {
  const json j = GridStateJson(SomeGrid());
  EXPECT_EQ(j.at("mode"), "tracking");
  EXPECT_EQ(j.at("seq"), 7);
  EXPECT_DOUBLE_EQ(j.at("offset_m").get<double>(), 0.012);
  EXPECT_DOUBLE_EQ(j.at("bearing_deg").get<double>(), -0.02 * 180.0 / std::numbers::pi);
  EXPECT_NEAR(j.at("offset_sd_m").get<double>(), 0.01, 1e-15);
  EXPECT_NEAR(j.at("bearing_sd_rad").get<double>(), 0.005, 1e-15);
  EXPECT_EQ(j.at("lines_in_view"), json::array({1, 2, 3}));
  EXPECT_EQ(j.at("validated"), 15);
}

TEST(GatewayConvert, GridSceneDrawsEachRowThroughItsPlantsInTheVehicleFrame) {
  const plantscale_grid_state_t m = SomeGrid();
  const json scene = GridSceneJson(m, 1);
  ASSERT_EQ(scene.at("entities").size(), 1u);
  const json& e = scene.at("entities")[0];
  EXPECT_EQ(e.at("frame_id"), "vehicle");
  ASSERT_EQ(e.at("lines").size(), 3u);    // rows -1, 0, 1
  ASSERT_EQ(e.at("spheres").size(), 9u);  // lines 1..3 on each
  // The central row's first plant (m = 1, n = 0): grid_model.h eq. A.1.
  const geometry::GridState s = FromLcm(m).state;
  const Eigen::Vector2d p = geometry::PlantInVehicle(s, 1, 0);
  const json& sphere = e.at("spheres")[3];
  // Scene geometry is rounded to 0.1 mm.
  EXPECT_NEAR(sphere.at("pose").at("position").at("x").get<double>(), p.x(), 0.5e-4 + 1e-12);
  EXPECT_NEAR(sphere.at("pose").at("position").at("y").get<double>(), p.y(), 0.5e-4 + 1e-12);
  // x = sin(psi) (m l + Y) + t_x: 0.012 + sin(-0.02) * (0.44 + 0.31).
  EXPECT_NEAR(p.x(), 0.012 + std::sin(-0.02) * 0.75, 1e-12);
}

TEST(GatewayConvert, PlantEllipseIsTheNinetyFivePercentContour) {
  PlantObservation p;
  p.id = 12;
  p.kind = PlantKind::kCrop;
  p.position_m = {2.0, 0.5};
  p.covariance << 4e-4, 0.0, 0.0, 1e-4;  // sd 2 cm along x, 1 cm along y
  p.size_m2 = 0.01;
  p.sprayed = true;
  const plantscale_plant_list_t list = ToLcm(std::vector<PlantObservation>{p}, 5'000'000, 3);
  const json scene = PlantsSceneJson(list);
  ASSERT_EQ(scene.at("entities").size(), 1u);
  const json& e = scene.at("entities")[0];
  EXPECT_EQ(e.at("id"), "plant/12");
  EXPECT_EQ(e.at("frame_id"), "field");
  const json& sphere = e.at("spheres")[0];
  // Scene geometry is rounded to 0.1 mm.
  EXPECT_NEAR(sphere.at("size").at("x").get<double>(), 2.0 * std::sqrt(0.01 / std::numbers::pi),
              0.5e-4 + 1e-12);
  EXPECT_DOUBLE_EQ(sphere.at("color").at("g").get<double>(), 0.75);  // crop green
  const json& loop = e.at("lines")[0];
  EXPECT_EQ(loop.at("type"), 1);  // LINE_LOOP
  ASSERT_EQ(loop.at("points").size(), 24u);
  double max_dx = 0.0;
  double max_dy = 0.0;
  for (const json& q : loop.at("points")) {
    const double dx = q.at("x").get<double>() - 2.0;
    const double dy = q.at("y").get<double>() - 0.5;
    max_dx = std::max(max_dx, std::abs(dx));
    max_dy = std::max(max_dy, std::abs(dy));
    // Every point on the contour: Mahalanobis distance squared = chi2(0.95, 2),
    // within what rounding to 0.1 mm moves it (2 |dx| / var * 0.05 mm, both
    // axes: at most 0.037).
    EXPECT_NEAR(dx * dx / 4e-4 + dy * dy / 1e-4, kChi2_95_2d, 0.04);
  }
  EXPECT_NEAR(max_dx, std::sqrt(kChi2_95_2d * 4e-4), 0.5e-4 + 1e-12);  // 4.90 cm
  EXPECT_NEAR(max_dy, std::sqrt(kChi2_95_2d * 1e-4), 0.5e-4 + 1e-12);  // 2.45 cm
  EXPECT_DOUBLE_EQ(loop.at("color").at("b").get<double>(), 1.0);       // sprayed: blue
}

TEST(GatewayConvert, MapTileBecomesAGridOfDecodedCells) {
  MapTileDelta t;
  t.tile_x = 3;
  t.tile_y = 1;
  t.origin_m = {2.56, 0.64};
  t.resolution_m = 0.01;
  t.width = 4;
  t.height = 2;
  t.cells = {1, 1, 2, 2, 3, 4, 4, 0};
  const json g = MapTileGridJson(ToLcm(t, 9'000'000));
  EXPECT_EQ(g.at("frame_id"), "field");
  EXPECT_EQ(g.at("column_count"), 4);
  EXPECT_EQ(g.at("row_stride"), 4);
  EXPECT_EQ(g.at("cell_stride"), 1);
  EXPECT_DOUBLE_EQ(g.at("cell_size").at("x").get<double>(), 0.01);
  EXPECT_DOUBLE_EQ(g.at("pose").at("position").at("x").get<double>(), 2.56);
  EXPECT_EQ(g.at("fields")[0].at("type"), 1);  // UINT8
  const uint8_t cells[] = {1, 1, 2, 2, 3, 4, 4, 0};
  EXPECT_EQ(g.at("data"), Base64(cells, 8));
  EXPECT_EQ(g.at("timestamp").at("sec"), 9);
}

TEST(GatewayConvert, ThumbnailIsACompressedJpeg) {
  plantscale_thumbnail_t m{};
  m.utime = 2'500'000;
  m.jpeg = {0xff, 0xd8, 0xff, 0xe0};
  m.jpeg_size = 4;
  const json j = ThumbnailJson(m);
  EXPECT_EQ(j.at("format"), "jpeg");
  EXPECT_EQ(j.at("data"), "/9j/4A==");
  EXPECT_EQ(j.at("timestamp").at("nsec"), 500'000'000);
}

TEST(GatewayConvert, EventSeverityMapsToLogLevels) {
  plantscale_event_t e{};
  e.utime = 1;
  e.kind = "command_refused";
  e.text = "forged (bad signature)";
  e.severity = plantscale_event_t::SEVERITY_WARNING;
  json j = EventLogJson(e);
  EXPECT_EQ(j.at("level"), 3);
  EXPECT_EQ(j.at("name"), "command_refused");
  EXPECT_EQ(j.at("message"), "forged (bad signature)");
  e.severity = plantscale_event_t::SEVERITY_ERROR;
  EXPECT_EQ(EventLogJson(e).at("level"), 4);
  e.severity = plantscale_event_t::SEVERITY_INFO;
  EXPECT_EQ(EventLogJson(e).at("level"), 2);
}

TEST(GatewayConvert, NozzlesCountOpenOnes) {
  NozzleBar bar;
  bar.open = {true, false, true, true};
  bar.fault = {0, 0, 2, 0};
  bar.failsafe = false;
  NozzleShot s;
  s.nozzle = 2;
  s.open_utime = 10;
  s.close_utime = 20;
  s.position_m = {1.5, -0.25};
  s.plant_id = 99;
  bar.shots = {s};
  const json j = NozzlesJson(ToLcm(bar, 100));
  EXPECT_EQ(j.at("open_count"), 3);
  EXPECT_EQ(j.at("fault"), json::array({0, 0, 2, 0}));
  EXPECT_EQ(j.at("shots")[0].at("plant_id"), 99);
  EXPECT_DOUBLE_EQ(j.at("shots")[0].at("y_m").get<double>(), -0.25);
}

TEST(GatewayConvert, CommandRoundTripsFieldForFieldWithItsMac) {
  plantscale_command_t c{};
  c.utime = 1'765'000'000'000'001;
  c.seq = 1'765'000'000'000'002;
  c.command = plantscale_command_t::COMMAND_SET_MODE;
  c.mode = plantscale_command_t::MODE_SPRAY_WEED;
  c.origin = "station@office";
  c.mac.resize(32);
  for (int i = 0; i < 32; ++i) c.mac[static_cast<size_t>(i)] = static_cast<uint8_t>(i * 7 + 1);
  c.mac_size = 32;
  const json j = CommandJson(c);
  EXPECT_EQ(j.at("mac").get<std::string>().substr(0, 6), "01080f");
  const plantscale_command_t back = CommandFromJson(j);
  EXPECT_EQ(Encode(back), Encode(c));  // the same bytes: a MAC over them still verifies
  json as_strings = j;
  as_strings["utime"] = std::to_string(c.utime);
  EXPECT_EQ(Encode(CommandFromJson(as_strings)), Encode(c));
}

TEST(GatewayConvert, BadCommandsAreRefusedNamingTheField) {
  const json good = {{"utime", 1}, {"seq", 2},      {"command", 1},
                     {"mode", 0},  {"origin", "s"}, {"mac", ""}};
  EXPECT_NO_THROW(CommandFromJson(good));
  const auto refused = [](json j, const std::string& field) {
    try {
      CommandFromJson(j);
      ADD_FAILURE() << "accepted " << j.dump();
    } catch (const DataError& e) {
      EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
    }
  };
  json j = good;
  j.erase("seq");
  refused(j, "seq");
  j = good;
  j["command"] = 300;
  refused(j, "command");
  j = good;
  j["mac"] = "abc";
  refused(j, "mac");
  j = good;
  j["mac"] = std::string(64, 'z');
  refused(j, "mac");
  j = good;
  j["utime"] = "12x";
  refused(j, "utime");
  refused(json::array(), "object");
}

TEST(GatewayConvert, ConvertLcmFeedsEveryTopicOfAChannel) {
  const Bytes bytes = Encode(SomeGrid());
  std::string error;
  const auto out = ConvertLcm(channels::kGrid, bytes.data(), bytes.size(), &error);
  EXPECT_TRUE(error.empty()) << error;
  ASSERT_EQ(out.size(), 2u);
  EXPECT_EQ(Topics()[static_cast<size_t>(out[0].topic)].name, "PLANTSCALE_GRID");
  EXPECT_EQ(Topics()[static_cast<size_t>(out[1].topic)].schema_name, "foxglove.SceneUpdate");
  EXPECT_EQ(out[0].utime, 1'700'000'000'123'456);
  EXPECT_EQ(json::parse(out[0].json).at("frame_index"), 42);
}

TEST(GatewayConvert, BadBytesAndNanAreReportedNotThrown) {
  std::string error;
  const uint8_t junk[] = {1, 2, 3};
  EXPECT_TRUE(ConvertLcm(channels::kGrid, junk, 3, &error).empty());
  EXPECT_NE(error.find("PLANTSCALE_GRID"), std::string::npos);
  plantscale_grid_state_t m = SomeGrid();
  m.state[0] = std::numeric_limits<double>::quiet_NaN();
  const Bytes bytes = Encode(m);
  error.clear();
  EXPECT_TRUE(ConvertLcm(channels::kGrid, bytes.data(), bytes.size(), &error).empty());
  EXPECT_NE(error.find("PLANTSCALE_GRID"), std::string::npos);
  error.clear();
  EXPECT_TRUE(ConvertLcm("SOMETHING_ELSE", junk, 3, &error).empty());
  EXPECT_TRUE(error.empty());
}

TEST(GatewayConvert, EventTextThatIsNotUtf8IsReplacedNotThrown) {
  plantscale_event_t e{};
  e.kind = "k";
  e.text = std::string("bad \xff\xfe bytes");
  const Bytes bytes = Encode(e);
  std::string error;
  const auto out = ConvertLcm(channels::kEvents, bytes.data(), bytes.size(), &error);
  ASSERT_EQ(out.size(), 1u);
  const json parsed = json::parse(out[0].json);
  EXPECT_EQ(parsed.at("message"), "bad \xEF\xBF\xBD\xEF\xBF\xBD bytes");  // U+FFFD for each
}

TEST(GatewayConvert, EveryTopicHasAnObjectSchemaNamedAsItsTitle) {
  ASSERT_GE(Topics().size(), 13u);
  for (const Topic& t : Topics()) {
    EXPECT_EQ(t.schema.at("type"), "object") << t.name;
    EXPECT_EQ(t.schema.at("title"), t.schema_name) << t.name;
    EXPECT_EQ(TopicIndex(t.name), &t - Topics().data());
  }
  EXPECT_EQ(Topics()[static_cast<size_t>(TopicIndex(channels::kThumbnail))].schema_name,
            "foxglove.CompressedImage");
  EXPECT_EQ(Topics()[static_cast<size_t>(TopicIndex(channels::kMapTiles))].schema_name,
            "foxglove.Grid");
  EXPECT_EQ(Topics()[static_cast<size_t>(TopicIndex(channels::kEvents))].schema_name,
            "foxglove.Log");
  EXPECT_EQ(Topics()[static_cast<size_t>(TopicIndex(channels::kPlants))].schema_name,
            "foxglove.SceneUpdate");
}

}  // namespace
}  // namespace plantscale::telemetry::gateway
