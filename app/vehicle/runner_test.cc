#include "app/vehicle/runner.h"

#include <gtest/gtest.h>
#include <plantscale_lcmtypes/plantscale_map_tile_t.hpp>
#include <plantscale_lcmtypes/plantscale_plant_t.hpp>

#include <algorithm>
#include <functional>
#include <opencv2/imgcodecs.hpp>
#include <plantscale_lcmtypes/plantscale_health_t.hpp>

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
  // The fail-safe's margins for the simulated crop's footprint (the
  // tracker is not told the crop's size here).
  po.treatment.close_on_uncertainty = true;
  const Eigen::Vector2d margin = po.treatment.UncertaintyMargin(so.field.crop_radius_m);
  po.treatment.uncertainty_margin_across_m = margin.x();
  po.treatment.uncertainty_margin_along_m = margin.y();
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
  // The records still in the last view were judged on the frames they had
  // (a plant line is in view over some 3 m): each confirmed crop among them
  // that the last list carries is a crop there.
  int judged = 0, judged_crops = 0;
  for (const treatment::PlantRecord& r : system.registry().records()) {
    if (!r.judged_at_end) continue;
    ++judged;
    if (!r.confirmed() || !r.crop()) continue;
    ++judged_crops;
    for (const PlantObservation& p : snap.plants) {
      if (p.id == r.id) {
        EXPECT_EQ(p.kind, PlantKind::kCrop) << r.id;
      }
    }
  }
  EXPECT_GE(judged_crops, 9);  // 3 rows × at least 3 lines in the last view
  EXPECT_GT(judged, judged_crops);
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
  CommandAuthOptions auth;
  auth.accept_unsigned = true;  // the script's commands are unsigned
  runner.ListenForCommands(t, auth);
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

namespace plantscale::vehicle {
namespace {

namespace channels = telemetry::channels;
using telemetry::Bytes;
using telemetry::CommandKey;
using telemetry::Decode;
using telemetry::Encode;
using telemetry::LcmTransport;
using telemetry::PublisherOptions;
using telemetry::Sign;

bool HasLine(const std::vector<std::string>& lines, const std::string& text) {
  return std::any_of(lines.begin(), lines.end(),
                     [&](const std::string& l) { return l.find(text) != std::string::npos; });
}

struct CommandRun {
  std::vector<OperatorCommands> seen;            // the state at each frame
  std::vector<std::vector<std::string>> faults;  // the heartbeat's faults at each frame
  std::vector<std::string> events;               // "kind: text"
  std::vector<std::string> health_faults;        // every fault line of every heartbeat sent
};

// Runs a short simulated pass with a heartbeat, `script` playing the
// station during each frame (its index from 0).
CommandRun RunWithStation(const CommandAuthOptions& auth, double length_m,
                          const std::function<void(Transport&, const VehicleFrame&, int)>& script) {
  class Script : public Stage {
   public:
    Script(Transport& t, CommandRun& run,
           const std::function<void(Transport&, const VehicleFrame&, int)>& script)
        : t_(t), run_(run), script_(script) {}
    std::string name() const override { return "station_script"; }
    void Process(const VehicleFrame& frame, RunStatus& status, Publisher&) override {
      run_.seen.push_back(status.commands);
      run_.faults.push_back(status.faults);
      script_(t_, frame, static_cast<int>(run_.seen.size()) - 1);
    }

   private:
    Transport& t_;
    CommandRun& run_;
    const std::function<void(Transport&, const VehicleFrame&, int)>& script_;
  };
  CommandRun run;
  LcmTransport t("memq://");
  t.Subscribe(channels::kEvents, [&](const ReceivedMessage& m) {
    const auto e = Decode<plantscale_event_t>(m.channel, m.data, m.size);
    if (e) run.events.push_back(e->kind + ": " + e->text);
  });
  t.Subscribe(channels::kHealth, [&](const ReceivedMessage& m) {
    const auto h = Decode<plantscale_health_t>(m.channel, m.data, m.size);
    if (h) run.health_faults.insert(run.health_faults.end(), h->faults.begin(), h->faults.end());
  });
  Publisher publisher(t, PublisherOptions{});
  sim::SimulatorOptions o = SmallPass();
  o.length_m = length_m;
  sim::Simulator simulator(o);
  SimFrameSource source(simulator, 1'700'000'000'000'000);
  VehicleRunner runner(publisher, RunnerOptions{false}, 1'700'000'000'000'000);
  runner.ListenForCommands(t, auth);
  runner.AddStage(std::make_unique<Script>(t, run, script));
  runner.AddStage(std::make_unique<HealthStage>());  // after the script: it sees the same faults
  runner.Run(source);
  while (t.Handle(0)) {
  }
  return run;
}

void Send(Transport& t, const plantscale_command_t& c) {
  const Bytes b = Encode(c);
  t.Publish(channels::kCommand, b.data(), b.size());
}

// Signed commands over memq://: the station's own are obeyed; a replayed,
// forged (flipped MAC byte, a field changed after signing, another key),
// stale (old or future timestamp), unsigned or out-of-order one is refused,
// leaves the state as it was, is a command_refused event and a fault line
// in the heartbeat for fault_hold_us. Timestamps against the message clock.
TEST(VehicleRunner, ObeysSignedCommandsAndRefusesForgedReplayedStaleAndUnsigned) {
  CommandKey key, other_key;
  key.bytes.fill(0x11);
  other_key.bytes.fill(0x22);
  CommandAuthOptions auth;
  auth.key = key;
  auth.fault_hold_us = 1'200'000;
  using C = plantscale_command_t;
  constexpr int kEvery = 6;  // frames between the steps (0.48 s: at most 3 refusals held at once)
  constexpr int kSteps = 12;
  Bytes recorded_pause;
  const auto script = [&](Transport& t, const VehicleFrame& frame, int index) {
    if (index % kEvery != 2 || index / kEvery >= kSteps) return;
    C c{};
    c.utime = frame.utime;
    c.origin = "test station";
    c.command = C::COMMAND_PAUSE;
    switch (index / kEvery) {
      case 0:  // obeyed, and recorded by the attacker
        c.seq = 100;
        Sign(c, key);
        recorded_pause = Encode(c);
        break;
      case 1:  // obeyed
        c.seq = 101, c.command = C::COMMAND_START;
        Sign(c, key);
        break;
      case 2:  // replayed: the recorded pause, byte for byte
        t.Publish(channels::kCommand, recorded_pause.data(), recorded_pause.size());
        return;
      case 3:  // forged: one bit of the MAC flipped
        c.seq = 102;
        Sign(c, key);
        c.mac[7] ^= 0x10;
        break;
      case 4:  // forged: the mode changed after signing
        c.seq = 103, c.command = C::COMMAND_SET_MODE, c.mode = C::MODE_SPRAY_WEED;
        Sign(c, key);
        c.mode = C::MODE_SPRAY_OFF;
        break;
      case 5:  // forged: signed with another key
        c.seq = 104;
        Sign(c, other_key);
        break;
      case 6:  // stale: 3 s old
        c.seq = 105, c.utime = frame.utime - 3'000'000;
        Sign(c, key);
        break;
      case 7:  // stale: 3 s ahead
        c.seq = 106, c.utime = frame.utime + 3'000'000;
        Sign(c, key);
        break;
      case 8:  // unsigned
        c.seq = 107;
        break;
      case 9:  // replayed: an older seq, freshly signed
        c.seq = 50, c.command = C::COMMAND_SET_MODE, c.mode = C::MODE_SPRAY_OFF;
        Sign(c, key);
        break;
      case 10:  // obeyed: seq 102 was never accepted (refusals consume nothing)
        c.seq = 102, c.command = C::COMMAND_SET_MODE, c.mode = C::MODE_SPRAY_WEED;
        Sign(c, key);
        break;
      case 11:  // replayed: the same seq again, a new command, freshly signed
        c.seq = 102, c.command = C::COMMAND_SET_MODE, c.mode = C::MODE_SPRAY_OFF;
        Sign(c, key);
        break;
    }
    Send(t, c);
  };
  const CommandRun run = RunWithStation(auth, 6.0, script);  // 0.7 m/s, 12.5 Hz: ≈ 107 frames
  ASSERT_GE(run.seen.size(), static_cast<size_t>(kEvery * kSteps + 20));
  // A command sent during frame k is applied (or not) before frame k + 1.
  const auto after = [&](int step) { return run.seen[static_cast<size_t>(step * kEvery + 3)]; };
  EXPECT_FALSE(run.seen[2].paused);
  EXPECT_TRUE(after(0).paused);
  EXPECT_FALSE(after(1).paused);
  for (int step = 2; step <= 9; ++step) {
    EXPECT_FALSE(after(step).held()) << "step " << step;  // not paused, not off
    EXPECT_EQ(after(step).mode, 0) << "step " << step;
  }
  EXPECT_EQ(after(10).mode, int8_t{C::MODE_SPRAY_WEED});
  EXPECT_FALSE(after(11).spray_off);
  EXPECT_EQ(after(11).mode, int8_t{C::MODE_SPRAY_WEED});
  EXPECT_EQ(run.seen.back().received, 3);
  EXPECT_EQ(run.seen.back().refused, 9);

  const std::vector<std::string> refusals = {
      "replayed (seq 100, not after the last accepted 101) from test station",
      "forged (bad signature) from test station",
      // 3 s and a frame's time apart: the vehicle checks before the next frame
      "stale (sent 3.",
      " s before the vehicle's clock, window ±2.0 s) from test station",
      " s after the vehicle's clock, window ±2.0 s) from test station",
      "unsigned (no signature) from test station",
      "replayed (seq 50, not after the last accepted 101) from test station",
      "replayed (seq 102, not after the last accepted 102) from test station",
  };
  // A line that starts with `prefix` and holds `why`.
  const auto has = [](const std::vector<std::string>& lines, const std::string& prefix, const std::string& why) {
    return std::any_of(lines.begin(), lines.end(), [&](const std::string& l) {
      return l.rfind(prefix, 0) == 0 && l.find(why) != std::string::npos;
    });
  };
  for (const std::string& why : refusals) {
    EXPECT_TRUE(has(run.events, "command_refused: ", why)) << why;
    EXPECT_TRUE(has(run.health_faults, "command refused: ", why)) << why;
  }
  EXPECT_EQ(std::count_if(run.events.begin(), run.events.end(),
                          [](const std::string& e) { return e.rfind("command_refused: ", 0) == 0; }),
            9);
  EXPECT_TRUE(HasLine(run.events, "command: paused (nozzles closed) by test station"));
  EXPECT_TRUE(HasLine(run.events, "command: mode: spray the weeds by test station"));
  EXPECT_FALSE(HasLine(run.events, "unverified"));
  // The fault line right after the refusal, gone fault_hold_us later.
  const size_t forged_at = 3 * kEvery + 3;
  EXPECT_TRUE(HasLine(run.faults[forged_at], "command refused: forged (bad signature) from test station"));
  EXPECT_FALSE(HasLine(run.faults[forged_at - 1], "command refused: forged"));
  EXPECT_FALSE(HasLine(run.faults.back(), "command refused"));
  for (const auto& f : run.faults) EXPECT_LE(f.size(), 4u);
}

// A flood of forged commands cannot fill the log: at most
// max_refusal_events command_refused events a period, the rest counted and
// reported once the period is over; every one is still refused and counted.
TEST(VehicleRunner, AFloodOfRefusedCommandsIsSummarisedOncePerPeriod) {
  CommandKey key;
  key.bytes.fill(0x11);
  CommandAuthOptions auth;
  auth.key = key;
  using C = plantscale_command_t;
  constexpr int kFlood = 1000;
  const auto script = [&](Transport& t, const VehicleFrame& frame, int index) {
    if (index != 3 && index != 30) return;
    for (int i = 0; i < (index == 3 ? kFlood : 1); ++i) {
      C c{};
      c.utime = frame.utime, c.seq = 1000 + i, c.origin = "yard laptop", c.command = C::COMMAND_PAUSE;
      Sign(c, key);
      c.mac[0] ^= 1;
      Send(t, c);
    }
  };
  const CommandRun run = RunWithStation(auth, 2.5, script);  // ≈ 45 frames, 3.6 s
  ASSERT_GE(run.seen.size(), 35u);
  EXPECT_EQ(run.seen.back().refused, kFlood + 1);
  for (const OperatorCommands& k : run.seen) EXPECT_FALSE(k.paused);
  std::vector<std::string> refused;
  for (const std::string& e : run.events) {
    if (e.rfind("command_refused: ", 0) == 0) refused.push_back(e);
  }
  // 4 at once, the summary of the other 996 a second (13 frames) later, the
  // lone one at frame 30 on its own.
  ASSERT_EQ(refused.size(), 6u);
  for (size_t i = 0; i < 4; ++i) {
    EXPECT_EQ(refused[i], "command_refused: forged (bad signature) from yard laptop");
  }
  EXPECT_EQ(refused[4].rfind("command_refused: 996 more commands refused in 1.", 0), 0u) << refused[4];
  EXPECT_NE(refused[4].find("(at most 4 per 1.0 s); the last: forged (bad signature) from yard laptop"),
            std::string::npos)
      << refused[4];
  EXPECT_EQ(refused[5], "command_refused: forged (bad signature) from yard laptop");
  for (const auto& f : run.faults) EXPECT_LE(f.size(), 4u);
}

// Fail closed: a vehicle without a key obeys no command, and says why;
// with accept_unsigned and a key, an unsigned command is obeyed but a bad
// signature still is not.
TEST(VehicleRunner, WithoutAKeyRefusesEveryCommand) {
  CommandKey key;
  key.bytes.fill(0x33);
  using C = plantscale_command_t;
  const auto script = [&](Transport& t, const VehicleFrame& frame, int index) {
    C c{};
    c.utime = frame.utime, c.seq = index, c.origin = "test station", c.command = C::COMMAND_PAUSE;
    if (index == 2) Send(t, c);  // unsigned
    if (index == 4) {  // signed, but the vehicle cannot check it
      Sign(c, key);
      Send(t, c);
    }
  };
  const CommandRun closed = RunWithStation(CommandAuthOptions{}, 1.0, script);
  ASSERT_GE(closed.seen.size(), 8u);
  for (const OperatorCommands& k : closed.seen) EXPECT_FALSE(k.paused);
  EXPECT_EQ(closed.seen.back().refused, 2);
  EXPECT_TRUE(HasLine(closed.events,
                      "command_refused: unsigned (no signature; the vehicle has no command key, --command-key) "
                      "from test station"));
  EXPECT_TRUE(HasLine(closed.events,
                      "command_refused: not verifiable (the vehicle has no command key, --command-key) from test "
                      "station"));

  CommandAuthOptions open;
  open.key = key;
  open.accept_unsigned = true;
  const auto mixed = [&](Transport& t, const VehicleFrame& frame, int index) {
    C c{};
    c.utime = frame.utime, c.seq = index, c.origin = "test station", c.command = C::COMMAND_PAUSE;
    if (index == 2) Send(t, c);  // unsigned: obeyed
    if (index == 4) {  // forged: refused
      c.command = C::COMMAND_START;
      Sign(c, key);
      c.mac[0] ^= 1;
      Send(t, c);
    }
  };
  const CommandRun demo = RunWithStation(open, 1.0, mixed);
  ASSERT_GE(demo.seen.size(), 8u);
  EXPECT_TRUE(demo.seen[3].paused);
  EXPECT_TRUE(demo.seen.back().paused);
  EXPECT_TRUE(HasLine(demo.events,
                      "command: paused (nozzles closed) by test station (unverified: --accept-unsigned-commands)"));
  EXPECT_TRUE(HasLine(demo.events, "command_refused: forged (bad signature) from test station"));
}

}  // namespace
}  // namespace plantscale::vehicle
