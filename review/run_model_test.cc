// The run model from messages we construct: offset trace, plant registry,
// heartbeat age and lost link, and the bad inputs the station must survive
// and explain (no messages, another program's log, vehicle restart, NaN).
#include <gtest/gtest.h>

#include <cmath>

#include "review/run_model.h"
#include "review/synthetic_run.h"
#include "review/test_util.h"
#include "telemetry/channels.h"
#include "telemetry/codec.h"
#include "telemetry/convert.h"

namespace plantscale::review {
namespace {

namespace tm = plantscale::telemetry;

bool Mentions(const std::vector<std::string>& lines, const std::string& what) {
  for (const std::string& l : lines) {
    if (l.find(what) != std::string::npos) return true;
  }
  return false;
}

// RunModel::Feed looks up only the tile a message carries; the model must
// end where a pass over every tile after each message ends, also when its
// subscriber keeps no tiles of its own (the station's replay and review).
TEST(RunModel, FeedWithTileLookUpMatchesFullPass) {
  SyntheticRunOptions run;
  run.length_m = 8.0;
  const std::vector<tm::LogEvent> events = SyntheticRun(run);
  tm::SubscriberOptions lean;
  lean.keep_tiles = false;
  tm::Subscriber sub_a(lean), sub_b;
  RunModel a, b;
  a.Follow(sub_a);
  b.Follow(sub_b);
  for (const tm::LogEvent& e : events) {
    a.Feed(sub_a, e.channel, e.data.data(), e.data.size(), e.utime);
    sub_b.Feed(e.channel, e.data.data(), e.data.size(), e.utime);
    ASSERT_EQ(a.tile_revision_sum(), b.tile_revision_sum());
  }
  ASSERT_GT(a.tiles().size(), 5u);
  EXPECT_EQ(sub_a.Snapshot().tiles.size(), 1u) << "the tile last received only";
  ASSERT_EQ(a.tiles().size(), b.tiles().size());
  for (const auto& [key, t] : b.tiles()) {
    ASSERT_TRUE(a.tiles().count(key));
    EXPECT_EQ(a.tiles().at(key).revision, t.revision);
    EXPECT_EQ(a.tiles().at(key).cells, t.cells);
  }
}

TEST(RunModel, EllipseScaleIsChiSquareTwoDof) {
  EXPECT_NEAR(EllipseScale2d(0.95), 5.991, 1e-3);  // χ²₂(0.95)
  EXPECT_NEAR(EllipseScale2d(0.99), 9.210, 1e-3);
  EXPECT_NEAR(EllipseScale2d(1.0 - std::exp(-0.5)), 1.0, 1e-12);  // 1σ contour
  EXPECT_THROW(EllipseScale2d(1.0), std::invalid_argument);
}

TEST(RunModel, TraceCarriesOffsetSigmaAndDistance) {
  tm::Subscriber sub;
  RunModel model;
  model.Follow(sub);
  plantscale_odometry_t odo{};
  odo.distance_m = 3.5;
  odo.valid = 1;
  const tm::Bytes o = tm::Encode(odo);
  sub.Feed(tm::channels::kOdometry, o.data(), o.size(), 1000);
  tm::GridEstimate g;
  g.state.offset_m = 0.012;
  g.covariance(0, 0) = 0.004 * 0.004;
  g.covariance(2, 2) = 0.01 * 0.01;
  const tm::Bytes b = tm::Encode(tm::ToLcm(g));
  sub.Feed(tm::channels::kGrid, b.data(), b.size(), 2000);
  ASSERT_EQ(model.trace().size(), 1u);
  EXPECT_DOUBLE_EQ(model.trace()[0].distance_m, 3.5);
  EXPECT_NEAR(model.trace()[0].offset_sigma_m, 0.004, 1e-12);
  EXPECT_NEAR(model.trace()[0].bearing_sigma_rad, 0.01, 1e-12);
}

// A grid estimate arrives after its frame was processed, and over a live
// link after the network's delay: drawn at the distance of its arrival,
// the tracker's trace would run ahead of the simulator's truth (published
// at the capture) by the speed times that delay. Each is drawn at the
// distance of its own time (here an estimate 16 s late, 11.2 m).
TEST(RunModel, ATraceSampleIsAtTheDistanceOfItsCaptureNotOfItsArrival) {
  tm::Subscriber sub;
  RunModel model;
  model.Follow(sub);
  // Odometry every 20 ms at 0.7 m/s from 2,600 m for 20 s.
  for (int i = 0; i <= 1000; ++i) {
    plantscale_odometry_t odo{};
    odo.utime = 1'000'000 + 20'000 * i;
    odo.distance_m = 2600.0 + 0.7 * 0.02 * i;
    odo.valid = 1;
    const tm::Bytes o = tm::Encode(odo);
    sub.Feed(tm::channels::kOdometry, o.data(), o.size(), odo.utime);
  }
  // The estimate of a frame captured at 5.01 s (2,602.807 m) arrives at the end.
  tm::GridEstimate g;
  g.utime = 5'010'000;
  const tm::Bytes b = tm::Encode(tm::ToLcm(g));
  sub.Feed(tm::channels::kGrid, b.data(), b.size(), 21'000'000);
  ASSERT_EQ(model.trace().size(), 1u);
  EXPECT_NEAR(model.distance_m(), 2614.0, 1e-9);
  EXPECT_NEAR(model.trace()[0].distance_m, 2600.0 + 0.7 * 4.01, 1e-6);
}

TEST(RunModel, NoMessagesIsSaid) {
  RunModel model;
  EXPECT_EQ(model.Link(123).level, LinkLevel::kNoMessages);
  EXPECT_TRUE(Mentions(model.Problems(123), "NO MESSAGES"));
}

TEST(RunModel, HeartbeatAgeAndLostLinkAtTheLimit) {
  SyntheticRunOptions o;
  o.heartbeat_stops_at_s = 3.0;
  LogTimeline run = testing::RunUpTo(o, 4.8);  // heartbeats every 6 frames (0.48 s): last at 2.88 s
  EXPECT_EQ(run.model().Link(run.now_utime()).level, LinkLevel::kOk);
  EXPECT_NEAR(run.model().Link(run.now_utime()).heartbeat_age_s, 1.92, 1e-6);
  run.Seek(5.0);  // 2.12 s > 2 s: lost
  EXPECT_EQ(run.model().Link(run.now_utime()).level, LinkLevel::kLost);
  EXPECT_TRUE(Mentions(run.model().Problems(run.now_utime()), "LINK LOST"));
}

TEST(RunModel, QuietAfterTheRunFinishedIsNotALostLink) {
  SyntheticRunOptions o;
  o.length_m = 2.0;  // 4 s at 0.5 m/s; run_finished at 4.0 s
  LogTimeline run = testing::RunUpTo(o, 4.0);
  run.Seek(run.duration_s());
  // A log replayed to its end: time stops with the last message.
  EXPECT_EQ(run.model().Link(run.now_utime()).level, LinkLevel::kFinished);
  const int64_t later = run.now_utime() + 10'000'000;
  const LinkStatus link = run.model().Link(later);
  EXPECT_EQ(link.level, LinkLevel::kFinished);
  EXPECT_TRUE(link.text.find("run finished after 51 frames") != std::string::npos) << link.text;
  EXPECT_GT(link.heartbeat_age_s, 10.0);
  EXPECT_FALSE(Mentions(run.model().Problems(later), "LINK LOST"));
  // A heartbeat that stops before the run ends is a lost link.
  o.heartbeat_stops_at_s = 1.0;
  LogTimeline cut = testing::RunUpTo(o, 3.9);
  EXPECT_EQ(cut.model().Link(cut.now_utime()).level, LinkLevel::kLost);
  EXPECT_TRUE(Mentions(cut.model().Problems(cut.now_utime()), "LINK LOST"));
}

// The vehicle's last plant list names the plants the bar never reached (the
// run ended first): the summary keeps them apart from the treated and the
// missed.
TEST(RunModel, PlantsTheBarNeverReachedAreCountedApart) {
  RunModel model;
  tm::TelemetrySnapshot s;
  s.channels[tm::channels::kPlants].last_recv_utime = 1'000'000;
  const auto plant = [](int64_t id, tm::PlantKind kind, bool sprayed, int why) {
    tm::PlantObservation p;
    p.id = id;
    p.kind = kind;
    p.sprayed = sprayed;
    p.why = why;
    return p;
  };
  s.plants = {plant(1, tm::PlantKind::kCrop, true, plantscale_plant_t::WHY_CROP_IN_REGION),
              plant(2, tm::PlantKind::kCrop, false, plantscale_plant_t::WHY_CROP_IN_REGION),
              plant(3, tm::PlantKind::kCrop, false, plantscale_plant_t::WHY_NOT_REACHED),
              plant(4, tm::PlantKind::kCrop, false, plantscale_plant_t::WHY_NOT_REACHED),
              plant(5, tm::PlantKind::kWeed, false, plantscale_plant_t::WHY_OUTSIDE_REGION)};
  model.Observe(tm::channels::kPlants, true, s);
  const RunSummary sum = model.Summary();
  EXPECT_EQ(sum.crop_seen, 4);
  EXPECT_EQ(sum.crop_treated, 1);
  EXPECT_EQ(sum.crop_not_reached, 2);  // crop 2 is a miss
  EXPECT_EQ(sum.weeds_not_reached, 0);
}

TEST(RunModel, VehicleRestartIsSaidAndCounted) {
  SyntheticRunOptions o;
  o.restart_at_s = 4.0;
  const LogTimeline run = testing::RunUpTo(o, 8.0);
  EXPECT_TRUE(Mentions(run.model().Problems(run.now_utime()), "restarted"));
  EXPECT_EQ(run.model().Summary().vehicle_restarts, 1);
  EXPECT_GT(run.model().trace().size(), 90u);  // the trace goes on after the restart
}

TEST(RunModel, NanMessageIsRejectedAndNamed) {
  SyntheticRunOptions o;
  o.nan_grid_at_s = 2.0;
  const LogTimeline run = testing::RunUpTo(o, 4.0);
  EXPECT_TRUE(Mentions(run.model().Problems(run.now_utime()), tm::channels::kGrid));
  for (const TraceSample& t : run.model().trace()) EXPECT_TRUE(std::isfinite(t.offset_m));
  EXPECT_TRUE(Mentions(run.model().Summary().faults, "bad messages"));
}

TEST(RunModel, LogFromAnotherProgramIsSaid) {
  std::vector<tm::LogEvent> events;
  for (int i = 0; i < 10; ++i) events.push_back({i, 1000 + i * 1000, "OTHER_PROGRAM", {1, 2, 3}});
  LogTimeline run(std::move(events), "");
  run.Seek(1.0);
  EXPECT_TRUE(Mentions(run.model().Problems(run.now_utime()), "no plantscale messages"));
}

TEST(RunModel, PlantRegistryKeepsEveryPlantOnce) {
  const LogTimeline run = testing::RunUpTo({}, 20.0);  // the whole 10 m run
  const RunSummary s = run.model().Summary();
  EXPECT_EQ(s.plants_seen, s.crop_seen + s.weeds_seen);
  // Crop at 0.45 m in three rows, seen up to 2.3 m ahead of the 10 m end.
  EXPECT_NEAR(s.crop_seen, 3 * static_cast<int>((10.0 + 2.3 - 0.5) / 0.45 + 1), 3);
}

}  // namespace
}  // namespace plantscale::review
