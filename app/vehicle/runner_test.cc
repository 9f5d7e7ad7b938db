#include "app/vehicle/runner.h"

#include <gtest/gtest.h>
#include <plantscale_lcmtypes/plantscale_map_tile_t.hpp>
#include <plantscale_lcmtypes/plantscale_plant_t.hpp>

#include <algorithm>
#include <opencv2/imgcodecs.hpp>

#include "app/vehicle/stages.h"
#include "engine/geometry/test_cameras.h"
#include "telemetry/channels.h"
#include "telemetry/subscriber.h"

namespace plantscale::vehicle {
namespace {

namespace channels = telemetry::channels;
using telemetry::Bytes;
using telemetry::Decode;
using telemetry::Encode;
using telemetry::LcmTransport;
using telemetry::PlantKind;
using telemetry::PlantObservation;
using telemetry::PublisherOptions;
using telemetry::Subscriber;
using telemetry::TelemetrySnapshot;

sim::SimulatorOptions SmallPass() {
  sim::SimulatorOptions o;
  o.preset = "unit-test";
  o.camera = geometry::testing::ThesisCamera();
  o.camera.focal_length_m = 0.0012;  // 160×120, same view
  o.camera.image_width_px = 160;
  o.camera.image_height_px = 120;
  o.length_m = 3.0;
  o.seed = 3;
  return o;
}

struct Published {
  RunSummary summary;
  TelemetrySnapshot snap;
  sim::FrameTruth last_truth;
};

Published RunFast() {
  LcmTransport t("memq://");
  Subscriber sub;
  sub.Attach(t);
  Publisher publisher(t, PublisherOptions{});
  sim::Simulator simulator(SmallPass());
  SimFrameSource source(simulator, 1'700'000'000'000'000);
  VehicleRunner runner(publisher, RunnerOptions{false}, 1'700'000'000'000'000);
  runner.AddStage(std::make_unique<HealthStage>());
  runner.AddStage(std::make_unique<OdometryStage>());
  auto segmentation = std::make_unique<SegmentationStage>();
  const SegmentationStage* blobs = segmentation.get();
  runner.AddStage(std::move(segmentation));
  runner.AddStage(std::make_unique<ThumbnailStage>(ThumbnailOptions{80, 60}, blobs));
  runner.AddStage(std::make_unique<SimTruthStage>());
  Published p;
  p.summary = runner.Run(source);
  while (t.Handle(0)) {
  }
  p.snap = sub.Snapshot();
  return p;
}

// The pipeline stage: a tick per odometry sample into
// the nozzle sink, the bar closed until the grid is tracked, then plants,
// nozzle states and shots on their channels.
TEST(VehicleRunner, PipelineStageSchedulesNozzlesFromTheTrackedGrid) {
  LcmTransport t("memq://");
  Subscriber sub;
  sub.Attach(t);
  Publisher publisher(t, PublisherOptions{});
  sim::SimulatorOptions so;
  so.camera = geometry::testing::ThesisCamera();
  so.length_m = 8.0;
  so.seed = 5;
  sim::Simulator simulator(so);
  SimFrameSource source(simulator, 1'700'000'000'000'000);
  VehicleRunner runner(publisher, RunnerOptions{false}, 1'700'000'000'000'000);
  pipeline::PipelineOptions po;
  po.tracker.rows_each_side = (so.field.rows - 1) / 2;
  po.tracker.row_spacing_m = so.field.row_spacing_m;
  po.tracker.plant_spacing_m = so.field.plant_spacing_m;
  po.tracker.track_width_m = so.vehicle.track_width_m;
  int ticks = 0, open_ticks = 0, open_while_lost = 0;
  const PipelineStage* stage_ptr = nullptr;
  auto stage_owned = std::make_unique<PipelineStage>(
      simulator.camera(), po, [&](int64_t, uint64_t mask) {
        ++ticks;
        open_ticks += mask != 0;
        open_while_lost += mask != 0 && stage_ptr->pipeline().tracker().mode() !=
                                            tracking::TrackerMode::kTracking;
      });
  stage_ptr = stage_owned.get();
  const PipelineStage& stage = *stage_owned;
  const tracking::GridTracker& tracker = stage.pipeline().tracker();
  const treatment::TreatmentSystem& system = *stage.pipeline().treatment();
  runner.AddStage(std::move(stage_owned));
  const RunSummary summary = runner.Run(source);
  while (t.Handle(0)) {
  }
  const TelemetrySnapshot snap = sub.Snapshot();
  ASSERT_GT(summary.frames, 100);
  // 50 Hz odometry over ≈ 8 m at the preset's speed: one tick per sample.
  EXPECT_GT(ticks, 4 * summary.frames - 10);
  ASSERT_EQ(tracker.mode(), tracking::TrackerMode::kTracking);
  EXPECT_GT(open_ticks, 20);  // crops passed under the bar
  EXPECT_EQ(open_while_lost, 0);
  EXPECT_GT(snap.channels.at(channels::kNozzles).received, 20);
  EXPECT_GT(snap.channels.at(channels::kPlants).received, 10);
  EXPECT_GT(snap.channels.at(channels::kMapTiles).received, 0);
  for (const auto& [name, stats] : snap.channels) {
    EXPECT_EQ(stats.decode_failures + stats.invalid, 0) << name;
  }
  // Crop records the bar has passed were sprayed (bed frame).
  const double bar_y = tracker.forward_distance_m() -
                       system.options().scheduler.bar.bar_offset_m;
  int crops = 0, sprayed = 0;
  for (const treatment::PlantRecord& r : system.registry().records()) {
    if (!r.crop() || r.bed_m.y() > bar_y - 0.1) continue;
    ++crops;
    sprayed += r.sprayed;
  }
  EXPECT_GT(crops, 10);
  EXPECT_GE(sprayed, 0.8 * crops) << sprayed << " of " << crops;
  // The last plant list, sent at the run's end, names the crops still ahead
  // of the bar as not reached, so the report tells them from misses.
  int not_reached = 0;
  for (const PlantObservation& p : snap.plants) {
    if (p.why != plantscale_plant_t::WHY_NOT_REACHED) continue;
    ++not_reached;
    EXPECT_EQ(p.kind, PlantKind::kCrop);
    EXPECT_FALSE(p.sprayed);
    EXPECT_GT(p.position_m.y(), bar_y);
  }
  EXPECT_GE(not_reached, 5);  // the camera looks 2–4 m past the bar, 3 rows
  // The tiles: treated cells where the bar sprayed, soil only where the
  // camera looked (the map behind the start is unknown, not soil).
  std::map<int, int> cells;
  double soil_min_y = 1e9;
  for (const auto& [id, tile] : snap.tiles) {
    for (int r = 0; r < tile.height; ++r) {
      for (int c = 0; c < tile.width; ++c) {
        const uint8_t v = tile.cells[static_cast<size_t>(r * tile.width + c)];
        ++cells[v];
        if (v == plantscale_map_tile_t::CELL_SOIL) {
          soil_min_y = std::min(soil_min_y, tile.origin_m.y() + (r + 0.5) * tile.resolution_m);
        }
      }
    }
  }
  EXPECT_GT(cells[plantscale_map_tile_t::CELL_TREATED], 100);
  EXPECT_GT(cells[plantscale_map_tile_t::CELL_SOIL], 1000);
  EXPECT_GT(cells[plantscale_map_tile_t::CELL_UNKNOWN], 1000);
  // The thesis camera's view starts about 0.5 m ahead of the vehicle, which
  // starts tracking at bed y ≈ 0: nothing behind it was seen.
  EXPECT_GT(soil_min_y, 0.0);
  // At the end of the run the rows the bar had not passed went too: the
  // map reaches past the vehicle, to where the camera last looked (its far
  // edge is some 2 m ahead; tiles are 0.85 m deep).
  double crop_max_y = -1e9;
  for (const auto& [id, tile] : snap.tiles) {
    for (int r = 0; r < tile.height; ++r) {
      for (int c = 0; c < tile.width; ++c) {
        if (tile.cells[static_cast<size_t>(r * tile.width + c)] != plantscale_map_tile_t::CELL_CROP) continue;
        crop_max_y = std::max(crop_max_y, tile.origin_m.y() + (r + 0.5) * tile.resolution_m);
      }
    }
  }
  EXPECT_GT(crop_max_y, tracker.forward_distance_m() + 0.5);
}

TEST(VehicleRunner, SimulatedRunPublishesTruthThumbnailsHealthAndEvents) {
  const Published p = RunFast();
  const auto& ch = p.snap.channels;
  ASSERT_GT(p.summary.frames, 20);
  // Truth at the frame rate: one per frame, none lost by the rate limit.
  EXPECT_EQ(ch.at(channels::kSimTruth).received, p.summary.frames);
  EXPECT_EQ(ch.at(channels::kSimTruthPose).received, p.summary.frames);
  EXPECT_EQ(ch.count(channels::kGrid), 0u) << "truth must never appear on the tracker channel";
  // Thumbnails and heartbeat at 2 Hz of message time (±1 for the ends).
  const double expected_2hz = 2.0 * p.summary.seconds;
  EXPECT_NEAR(static_cast<double>(ch.at(channels::kThumbnail).received), expected_2hz, 1.5);
  EXPECT_NEAR(static_cast<double>(ch.at(channels::kHealth).received), expected_2hz, 1.5);
  for (const auto& [name, stats] : ch) {
    EXPECT_EQ(stats.decode_failures + stats.invalid + stats.lost, 0) << name;
  }
  ASSERT_TRUE(p.snap.thumbnail.has_value());
  const cv::Mat jpeg = cv::imdecode(p.snap.thumbnail->jpeg, cv::IMREAD_UNCHANGED);
  EXPECT_EQ(jpeg.cols, 80);
  EXPECT_EQ(jpeg.rows, 60);
  // The segmentation stage's blobs ride along, in full-size pixels.
  const plantscale_thumbnail_t& th = *p.snap.thumbnail;
  ASSERT_GT(th.num_blobs, 0);
  ASSERT_EQ(th.blobs.size(), static_cast<size_t>(th.num_blobs));
  for (const plantscale_blob_t& b : th.blobs) {
    EXPECT_GE(b.u, 0.0f);
    EXPECT_LE(b.u, static_cast<float>(th.source_width));
    EXPECT_GE(b.v, 0.0f);
    EXPECT_LE(b.v, static_cast<float>(th.source_height));
    EXPECT_GE(b.area_px, 1);
  }
  ASSERT_TRUE(p.snap.health.has_value());
  EXPECT_NEAR(p.snap.health->frame_rate_hz, 12.5, 0.5);  // preset frame rate, jitter ±4 %
  EXPECT_EQ(p.snap.health->source, "simulate");
  EXPECT_TRUE(p.snap.health->failsafe);  // no treatment stage: nozzles closed
  ASSERT_GE(p.snap.events.size(), 2u);
  EXPECT_EQ(p.snap.events.front().kind, "run_started");
  EXPECT_EQ(p.snap.events.back().kind, "run_finished");
  ASSERT_TRUE(p.snap.odometry.has_value());
  EXPECT_NEAR(p.snap.odometry->distance_m, 3.0, 0.3);  // odometry noise and slip: 10 %
}

// Plays the station: publishes a command while frame `at` is processed.
class StationScript : public Stage {
 public:
  StationScript(Transport& t, std::vector<OperatorCommands>& seen) : t_(t), seen_(seen) {}
  std::string name() const override { return "station_script"; }
  void Process(const VehicleFrame&, RunStatus& status, Publisher&) override {
    seen_.push_back(status.commands);
    const int frame = static_cast<int>(seen_.size());
    plantscale_command_t c{};
    c.origin = "test station";
    if (frame == 3) c.command = plantscale_command_t::COMMAND_PAUSE;
    if (frame == 5) c.command = plantscale_command_t::COMMAND_START;
    if (frame == 7) c.command = plantscale_command_t::COMMAND_SET_MODE, c.mode = plantscale_command_t::MODE_SPRAY_WEED;
    if (frame == 9) c.command = plantscale_command_t::COMMAND_SET_MODE, c.mode = plantscale_command_t::MODE_SPRAY_OFF;
    if (frame == 11) c.command = 42;  // unknown
    if (frame == 13) {
      const uint8_t junk[3] = {1, 2, 3};
      t_.Publish(channels::kCommand, junk, sizeof junk);
      return;
    }
    if (c.command != 0) {
      const Bytes b = Encode(c);
      t_.Publish(channels::kCommand, b.data(), b.size());
    }
  }

 private:
  Transport& t_;
  std::vector<OperatorCommands>& seen_;
};

TEST(VehicleRunner, ActsOnStationCommandsAndRefusesBadOnes) {
  LcmTransport t("memq://");
  std::vector<std::string> events;
  t.Subscribe(channels::kEvents, [&](const ReceivedMessage& m) {
    const auto e = Decode<plantscale_event_t>(m.channel, m.data, m.size);
    if (e) events.push_back(e->kind + ": " + e->text);
  });
  Publisher publisher(t, PublisherOptions{});
  sim::SimulatorOptions o = SmallPass();
  o.length_m = 1.5;
  sim::Simulator simulator(o);
  SimFrameSource source(simulator, 1'700'000'000'000'000);
  VehicleRunner runner(publisher, RunnerOptions{false}, 1'700'000'000'000'000);
  runner.ListenForCommands(t);
  std::vector<OperatorCommands> seen;
  runner.AddStage(std::make_unique<StationScript>(t, seen));
  runner.Run(source);
  ASSERT_GE(seen.size(), 15u);
  // A command sent during frame k is applied before frame k + 1.
  EXPECT_FALSE(seen[2].paused);
  EXPECT_TRUE(seen[3].paused);
  EXPECT_TRUE(seen[3].held());
  EXPECT_FALSE(seen[5].paused);
  EXPECT_EQ(seen[6].mode, 0);
  EXPECT_EQ(seen[7].mode, int8_t{plantscale_command_t::MODE_SPRAY_WEED});
  EXPECT_FALSE(seen[8].held());
  EXPECT_TRUE(seen[9].spray_off);
  EXPECT_TRUE(seen[9].held());
  EXPECT_EQ(seen[9].mode, int8_t{plantscale_command_t::MODE_SPRAY_WEED});  // off keeps the last mode
  EXPECT_EQ(seen.back().received, 4);
  EXPECT_EQ(seen.back().refused, 2);
  const auto has = [&](const std::string& text) {
    return std::any_of(events.begin(), events.end(), [&](const std::string& e) { return e.find(text) != std::string::npos; });
  };
  EXPECT_TRUE(has("command: paused (nozzles closed) by test station"));
  EXPECT_TRUE(has("command: mode: spray the weeds by test station"));
  EXPECT_TRUE(has("command_refused: command from test station: unknown command 42"));
  EXPECT_TRUE(has("command_refused: channel PLANTSCALE_COMMAND: cannot decode 3 bytes"));
}

// What the run was made from goes out once, right after run_started, so
// that its log can be scored later; nothing when not given.
TEST(VehicleRunner, RunConfigEventFollowsRunStarted) {
  for (const std::string& config : {std::string(R"({"preset": "unit-test", "seed": 3})"), std::string()}) {
    LcmTransport t("memq://");
    std::vector<plantscale_event_t> events;
    t.Subscribe(channels::kEvents, [&](const ReceivedMessage& m) {
      if (const auto e = Decode<plantscale_event_t>(m.channel, m.data, m.size)) events.push_back(*e);
    });
    Publisher publisher(t, PublisherOptions{});
    sim::SimulatorOptions o = SmallPass();
    o.length_m = 0.5;
    sim::Simulator simulator(o);
    SimFrameSource source(simulator, 1'700'000'000'000'000);
    RunnerOptions ro;
    ro.real_time = false;
    ro.run_config = config;
    VehicleRunner runner(publisher, ro, 1'700'000'000'000'000);
    runner.Run(source);
    while (t.Handle(0)) {
    }
    ASSERT_GE(events.size(), 2u);
    EXPECT_EQ(events[0].kind, "run_started");
    const auto configs = std::count_if(events.begin(), events.end(), [](const plantscale_event_t& e) {
      return e.kind == "run_config";
    });
    if (config.empty()) {
      EXPECT_EQ(configs, 0);
    } else {
      EXPECT_EQ(configs, 1);
      EXPECT_EQ(events[1].kind, "run_config");
      EXPECT_EQ(events[1].text, config);
      EXPECT_EQ(events[1].severity, int8_t{plantscale_event_t::SEVERITY_INFO});
    }
  }
}

}  // namespace
}  // namespace plantscale::vehicle
