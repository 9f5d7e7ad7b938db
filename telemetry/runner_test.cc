#include "telemetry/runner.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <opencv2/imgcodecs.hpp>

#include "engine/geometry/test_cameras.h"
#include "telemetry/channels.h"
#include "telemetry/stages.h"
#include "telemetry/subscriber.h"

namespace plantscale::telemetry {
namespace {

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

}  // namespace
}  // namespace plantscale::telemetry
