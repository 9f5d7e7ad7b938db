// Writes the seed corpora of the fuzz targets (tests/fuzz/corpus/<target>/):
// small valid inputs from the project's own writers, so that the fuzzers
// start from the formats' real structure. Run from the source tree:
//   cmake --build build --target fuzz_make_seeds && build/tests/fuzz/fuzz_make_seeds tests/fuzz/corpus
// Output is deterministic; the committed files are its output.
#include <plantscale_lcmtypes/plantscale_blob_t.hpp>
#include <plantscale_lcmtypes/plantscale_command_t.hpp>
#include <plantscale_lcmtypes/plantscale_event_t.hpp>
#include <plantscale_lcmtypes/plantscale_odometry_t.hpp>
#include <plantscale_lcmtypes/plantscale_shot_t.hpp>
#include <plantscale_lcmtypes/plantscale_thumbnail_t.hpp>

#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "maps/map_file.h"
#include "telemetry/can/protocol.h"
#include "telemetry/channels.h"
#include "telemetry/codec.h"
#include "telemetry/convert.h"
#include "telemetry/log.h"

namespace fs = std::filesystem;
namespace tel = plantscale::telemetry;
namespace ch = plantscale::telemetry::channels;
namespace can = plantscale::telemetry::can;
using Bytes = std::vector<uint8_t>;

namespace {

fs::path g_root;

void Write(const std::string& target, const std::string& name, const Bytes& bytes) {
  const fs::path dir = g_root / target;
  fs::create_directories(dir);
  std::ofstream out(dir / name, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  if (!out) throw std::runtime_error("cannot write " + (dir / name).string());
}

Bytes Prefixed(uint8_t first, const Bytes& rest) {
  Bytes b{first};
  b.insert(b.end(), rest.begin(), rest.end());
  return b;
}

Bytes ReadFile(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return Bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

// --- LCM messages, one of each type (lcm_fuzz: byte 0 picks the type) ----

struct Messages {
  plantscale_grid_state_t grid;
  plantscale_pose_t pose;
  plantscale_plant_list_t plants;
  plantscale_map_tile_t tile;
  plantscale_nozzles_t nozzles;
  plantscale_health_t health;
  plantscale_thumbnail_t thumbnail;
  plantscale_odometry_t odometry;
  plantscale_command_t command;
  plantscale_event_t event;
};

Messages MakeMessages() {
  Messages m;
  tel::GridEstimate e;
  e.utime = 1'000'000;
  e.frame_index = 3;
  e.state.row_spacing_m = 0.5;
  e.state.plant_spacing_m = 0.3;
  e.covariance = plantscale::geometry::Matrix5d::Identity() * 1e-4;
  e.mode = tel::FilterMode::kTracking;
  e.lines_in_view = {-1, 0, 1};
  e.observations = 7;
  e.validated = 6;
  m.grid = tel::ToLcm(e);

  tel::Pose pose{1.5, -0.2, 0.01, Eigen::Matrix3d::Identity() * 1e-3};
  m.pose = tel::ToLcm(pose, 1'000'000);

  tel::PlantObservation crop;
  crop.id = 1;
  crop.kind = tel::PlantKind::kCrop;
  crop.position_m = {0.1, 1.2};
  crop.covariance = Eigen::Matrix2d::Identity() * 1e-4;
  crop.size_m2 = 0.01;
  tel::PlantObservation weed = crop;
  weed.id = 2;
  weed.kind = tel::PlantKind::kWeed;
  weed.sprayed = true;
  weed.why = 2;
  m.plants = tel::ToLcm({crop, weed}, 1'000'000, 3);

  tel::MapTileDelta tile;
  tile.tile_x = 1;
  tile.tile_y = 2;
  tile.revision = 1;
  tile.width = 8;
  tile.height = 4;
  tile.cells.assign(32, 1);
  tile.cells[9] = 2;
  tile.cells[20] = 3;
  m.tile = tel::ToLcm(tile, 1'000'000);

  tel::NozzleBar bar;
  bar.open = {true, false, false, true};
  bar.fault = {0, 0, 2, 0};
  bar.failsafe = false;
  bar.shots.push_back({0, 1'000'000, 1'050'000, {0.1, 1.2}, 2});
  m.nozzles = tel::ToLcm(bar, 1'000'000);

  tel::Health health;
  health.source = "simulate";
  health.boot_utime = 1;
  health.frame_rate_hz = 12.5;
  health.frames = 40;
  health.distance_m = 2.0;
  health.faults = {"spray bar fuzz: no heartbeat"};
  m.health = tel::ToLcm(health, 1'000'000);

  cv::Mat grey(8, 8, CV_8UC1, cv::Scalar(60));
  cv::circle(grey, {4, 4}, 2, cv::Scalar(200), -1);
  std::vector<uchar> jpeg;
  cv::imencode(".jpg", grey, jpeg);
  m.thumbnail = plantscale_thumbnail_t{};
  m.thumbnail.utime = 1'000'000;
  m.thumbnail.frame_index = 3;
  m.thumbnail.source_width = 640;
  m.thumbnail.source_height = 480;
  m.thumbnail.width = 8;
  m.thumbnail.height = 8;
  m.thumbnail.jpeg.assign(jpeg.begin(), jpeg.end());
  m.thumbnail.jpeg_size = static_cast<int32_t>(jpeg.size());
  m.thumbnail.blobs.push_back({320.0f, 240.0f, 150, 1});
  m.thumbnail.num_blobs = 1;

  m.odometry = plantscale_odometry_t{};
  m.odometry.utime = 1'000'000;
  m.odometry.left_m_s = 0.5;
  m.odometry.right_m_s = 0.51;
  m.odometry.distance_m = 2.0;
  m.odometry.valid = 1;

  m.command = plantscale_command_t{};
  m.command.utime = 1'000'000;
  m.command.command = plantscale_command_t::COMMAND_SET_MODE;
  m.command.mode = plantscale_command_t::MODE_SPRAY_WEED;
  m.command.origin = "station";

  m.event = plantscale_event_t{};
  m.event.utime = 1'000'000;
  m.event.severity = plantscale_event_t::SEVERITY_WARNING;
  m.event.kind = "frame_dropped";
  m.event.text = "camera frame 12 dropped";
  return m;
}

void LcmSeeds(const Messages& m) {
  const std::string t = "lcm_fuzz";
  Write(t, "00-grid_state", Prefixed(0, tel::Encode(m.grid)));
  Write(t, "01-pose", Prefixed(1, tel::Encode(m.pose)));
  Write(t, "02-plant_list", Prefixed(2, tel::Encode(m.plants)));
  Write(t, "03-map_tile", Prefixed(3, tel::Encode(m.tile)));
  Write(t, "04-nozzles", Prefixed(4, tel::Encode(m.nozzles)));
  Write(t, "05-health", Prefixed(5, tel::Encode(m.health)));
  Write(t, "06-thumbnail", Prefixed(6, tel::Encode(m.thumbnail)));
  Write(t, "07-odometry", Prefixed(7, tel::Encode(m.odometry)));
  Write(t, "08-command", Prefixed(8, tel::Encode(m.command)));
  Write(t, "09-event", Prefixed(9, tel::Encode(m.event)));
  Write(t, "10-plant", Prefixed(10, tel::Encode(m.plants.plants[0])));
  Write(t, "11-shot", Prefixed(11, tel::Encode(m.nozzles.shots[0])));
  Write(t, "12-blob", Prefixed(12, tel::Encode(m.thumbnail.blobs[0])));
  Write(t, "13-sim_truth", Prefixed(13, tel::Encode(tel::TruthToLcm({}, 1'000'000, 3))));
  Write(t, "14-sim_truth_pose", Prefixed(14, tel::Encode(m.pose)));
}

// --- an LCM log: every channel once, then the same log cut short ----------

void LogSeeds(const Messages& m) {
  const fs::path tmp = fs::temp_directory_path() / "plantscale-fuzz-seed.lcmlog";
  {
    tel::LogWriter log(tmp);
    int64_t t = 1'000'000;
    auto put = [&](const char* channel, const Bytes& b) { log.Write(channel, b.data(), b.size(), t += 80'000); };
    put(ch::kHealth, tel::Encode(m.health));
    put(ch::kGrid, tel::Encode(m.grid));
    put(ch::kSimTruth, tel::Encode(tel::TruthToLcm({}, 1'000'000, 3)));
    put(ch::kPose, tel::Encode(m.pose));
    put(ch::kPlants, tel::Encode(m.plants));
    put(ch::kMapTiles, tel::Encode(m.tile));
    put(ch::kNozzles, tel::Encode(m.nozzles));
    put(ch::kThumbnail, tel::Encode(m.thumbnail));
    put(ch::kOdometry, tel::Encode(m.odometry));
    put(ch::kCommand, tel::Encode(m.command));
    put(ch::kEvents, tel::Encode(m.event));
    put("OTHER_PROGRAM", Bytes{1, 2, 3});
  }
  const Bytes whole = ReadFile(tmp);
  fs::remove(tmp);
  Write("log_fuzz", "whole.lcmlog", whole);
  Write("log_fuzz", "cut.lcmlog", Bytes(whole.begin(), whole.begin() + static_cast<long>(whole.size() / 3)));
}

// --- CAN: a bar's session (can_fuzz's record format) ----------------------

void CanSeeds() {
  const can::ProtocolIds ids;  // 0x210
  const uint16_t block = static_cast<uint16_t>(ids.base_id / 8);
  Bytes session{static_cast<uint8_t>(block & 0xff), static_cast<uint8_t>(block >> 8), 7};  // 8 nozzles
  auto frame = [&](const can_frame& f) {
    session.push_back(0);
    const auto* p = reinterpret_cast<const uint8_t*>(&f);
    session.insert(session.end(), p, p + sizeof f);
  };
  auto tick = [&](uint8_t ms) {
    session.push_back(3);
    session.push_back(ms);
  };
  auto command = [&](uint64_t mask) {
    session.push_back(2);
    for (int i = 0; i < 8; ++i) session.push_back(static_cast<uint8_t>(mask >> (8 * i)));
  };
  can::BarHeartbeat hb;
  hb.num_nozzles = 8;
  for (uint8_t k = 0; k < 4; ++k) {
    hb.counter = k;
    frame(can::Encode(ids, hb));
    tick(50);
  }
  command(0x0F);
  can::NozzleAck ack;
  ack.seq = 0;
  ack.applied_mask = 0x0F;
  frame(can::Encode(ids, ack));
  can::NozzleFaults faults;
  faults.fault[2] = can::NozzleFault::kStuck;
  frame(can::Encode(ids, faults));
  tick(20);
  command(0x81);
  can::NozzleCommand cmd;  // a command from the bar side: refused
  cmd.hold_ms = 200;
  frame(can::Encode(ids, cmd));
  session.push_back(1);  // a short datagram
  session.push_back(5);
  session.insert(session.end(), {0x10, 0x02, 0, 0, 4});
  tick(255);
  Write("can_fuzz", "session", session);
}

// --- a native map file: a raw file (byte 0 odd) and a payload (byte 0 even)

void MapSeeds() {
  plantscale::maps::MapGridOptions o;
  o.resolution_m = 0.05;
  o.origin_m = {-0.1, 0.0};
  o.cols = 4;
  o.rows = 3;
  plantscale::maps::CropMap map{plantscale::maps::MapGrid(o)};
  plantscale::maps::MapPlant crop;
  crop.id = 1;
  crop.position_m = {0.0, 0.05};
  crop.kind = plantscale::maps::PlantKind::kCrop;
  crop.radius_m = 0.03;
  map.AddPlant(crop);
  plantscale::maps::MapPlant weed = crop;
  weed.id = 2;
  weed.position_m = {0.06, 0.1};
  weed.kind = plantscale::maps::PlantKind::kWeed;
  weed.treated = true;
  weed.why = "outside region";
  map.AddPlant(weed);
  map.AddRow({0, {{0.0, 0.0}, {0.0, 0.15}}});
  map.SetMetadata("source", "fuzz seed");
  std::ostringstream out;
  plantscale::maps::WriteMap(map, out, "seed.psmap");
  const std::string file = out.str();
  Write("map_file_fuzz", "file", Prefixed(1, Bytes(file.begin(), file.end())));
  const std::string payload = file.substr(file.find('\n') + 1);
  Write("map_file_fuzz", "payload", Prefixed(0, Bytes(payload.begin(), payload.end())));
}

// --- photographs for `segment`: tiny PNGs and a JPEG ----------------------

void SegmentSeeds() {
  cv::Mat colour(24, 32, CV_8UC3, cv::Scalar(60, 80, 110));  // brown soil (BGR)
  cv::circle(colour, {10, 12}, 5, cv::Scalar(40, 170, 60), -1);
  cv::circle(colour, {24, 8}, 3, cv::Scalar(50, 150, 70), -1);
  cv::Mat grey;
  cv::cvtColor(colour, grey, cv::COLOR_BGR2GRAY);
  cv::Mat nir(24, 32, CV_8UC1, cv::Scalar(50));
  cv::circle(nir, {16, 12}, 6, cv::Scalar(210), -1);
  cv::Mat nir16;
  nir.convertTo(nir16, CV_16U, 257.0);
  cv::Mat bgra;
  cv::cvtColor(colour, bgra, cv::COLOR_BGR2BGRA);
  auto encode = [](const char* ext, const cv::Mat& image) {
    std::vector<uchar> b;
    cv::imencode(ext, image, b);
    return Bytes(b.begin(), b.end());
  };
  Write("segment_fuzz", "colour.png", Prefixed(0, encode(".png", colour)));    // auto, exg
  Write("segment_fuzz", "exgr.png", Prefixed(5, encode(".png", colour)));      // exg, exgr
  Write("segment_fuzz", "nir.png", Prefixed(2, encode(".png", nir)));          // nir
  Write("segment_fuzz", "adaptive.png", Prefixed(3, encode(".png", grey)));    // adaptive
  Write("segment_fuzz", "nir16.png", Prefixed(12, encode(".png", nir16)));     // 16-bit, min area
  Write("segment_fuzz", "bgra.png", Prefixed(8, encode(".png", bgra)));        // 4 channels, cive
  Write("segment_fuzz", "colour.jpg", Prefixed(0, encode(".jpg", colour)));
}

// --- YAML: a preset and a camera from config/ -----------------------------

void ConfigSeeds(const fs::path& config_dir) {
  Write("config_fuzz", "preset-sanchiz_pla.yaml", ReadFile(config_dir / "presets/sanchiz_pla.yaml"));
  Write("config_fuzz", "preset-treatment.yaml", ReadFile(config_dir / "presets/treatment.yaml"));
  Write("config_fuzz", "camera-thesis.yaml", ReadFile(config_dir / "cameras/thesis.yaml"));
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s CORPUS_DIR (tests/fuzz/corpus)\n", argv[0]);
    return 2;
  }
  g_root = argv[1];
  const Messages m = MakeMessages();
  LcmSeeds(m);
  LogSeeds(m);
  CanSeeds();
  MapSeeds();
  SegmentSeeds();
  ConfigSeeds(PLANTSCALE_SOURCE_CONFIG_DIR);
  std::printf("seeds written to %s\n", argv[1]);
  return 0;
}
