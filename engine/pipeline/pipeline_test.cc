// The vehicle pipeline on the simulator: frames classified and placed with
// the grid at their capture whatever odometry came in before them, and bad
// input (frames out of order or without an image, odometry that stops, a lost
// grid) reported with the bar closed, never thrown.
#include "engine/pipeline/pipeline.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <deque>
#include <functional>
#include <limits>

#include "engine/geometry/test_cameras.h"
#include "engine/sim/simulator.h"

#include <opencv2/imgproc.hpp>

namespace plantscale::pipeline {
namespace {

sim::SimulatorOptions Pass(double length_m) {
  sim::SimulatorOptions so;
  so.camera = geometry::testing::ThesisCamera();
  so.length_m = length_m;
  so.seed = 5;
  return so;
}

PipelineOptions OptionsFor(const sim::SimulatorOptions& so) {
  PipelineOptions o;
  o.tracker.rows_each_side = (so.field.rows - 1) / 2;
  o.tracker.row_spacing_m = so.field.row_spacing_m;
  o.tracker.plant_spacing_m = so.field.plant_spacing_m;
  o.tracker.track_width_m = so.vehicle.track_width_m;
  // The fail-safe's margins for the simulated crop's footprint (the
  // tracker is not told the crop's size here).
  o.treatment.close_on_uncertainty = true;
  const Eigen::Vector2d margin = o.treatment.UncertaintyMargin(so.field.crop_radius_m);
  o.treatment.uncertainty_margin_across_m = margin.x();
  o.treatment.uncertainty_margin_along_m = margin.y();
  return o;
}

OdometrySample Sample(const sim::OdometrySample& o) { return {o.utime, o.left_m_s, o.right_m_s}; }

struct Outcome {
  std::vector<treatment::PlantRecord> records;
  std::vector<double> capture_error_m;  // per tracked frame: Y at capture less Y of truth
  int frames_tracked = 0;
  int open_ticks = 0;
  int max_window_rows = 0;  // treatment map rows held at once
  int first_row = 0;        // the first row held at the end
};

// Drives a pass through a pipeline, each frame handed over once the
// odometry has passed its capture by `lag_us`.
Outcome Drive(double length_m, int64_t lag_us) {
  const sim::SimulatorOptions so = Pass(length_m);
  sim::Simulator simulator(so);
  Outcome run;
  Pipeline p(simulator.camera(), OptionsFor(so),
             [&run](int64_t, uint64_t mask) { run.open_ticks += mask != 0; });
  std::deque<sim::SimFrame> pending;
  const auto process = [&] {
    const sim::SimFrame& f = pending.front();
    const FrameResult& r = p.ProcessFrame(f.truth.utime, f.truth.index, f.rendered.image);
    const treatment::TreatmentMap& map = p.treatment()->map();
    run.max_window_rows = std::max(run.max_window_rows, map.rows() - map.first_row());
    EXPECT_TRUE(r.accepted) << (r.faults.empty() ? "" : r.faults.front());
    if (r.mode == tracking::TrackerMode::kTracking && r.report.updated) {
      ++run.frames_tracked;
      run.capture_error_m.push_back(
          std::remainder(r.state.forward_m - f.truth.grid.forward_m, f.truth.grid.plant_spacing_m));
    }
    pending.pop_front();
  };
  sim::SimFrame frame;
  while (simulator.Next(frame)) {
    std::vector<sim::OdometrySample> odometry = std::move(frame.odometry);
    pending.push_back(std::move(frame));
    frame = sim::SimFrame{};
    for (const sim::OdometrySample& o : odometry) {
      while (!pending.empty() && pending.front().truth.utime + lag_us < o.utime) process();
      p.AddOdometry(Sample(o));
    }
  }
  while (!pending.empty()) process();
  run.records = p.treatment()->registry().records();
  run.first_row = p.treatment()->map().first_row();
  return run;
}

double Mean(const std::vector<double>& v) {
  double s = 0.0;
  for (double x : v) s += x;
  return v.empty() ? std::numeric_limits<double>::infinity() : s / static_cast<double>(v.size());
}

// A frame that reaches the pipeline 100 ms after its capture, after the
// odometry up to then (about 70 mm of travel): its blobs are classified and
// placed with the grid where it stood at capture. Moved on by the lag, the
// crops would be placed 70 mm off along the row.
TEST(Pipeline, FrameLateBehindItsOdometryIsPlacedWithTheGridAtCapture) {
  const Outcome on_time = Drive(8.0, 0);
  const Outcome late = Drive(8.0, 100'000);
  ASSERT_GT(on_time.frames_tracked, 50);
  ASSERT_GT(late.frames_tracked, 50);
  // The grid reported with the frame is the grid at capture: its error in Y
  // against the truth at capture is the on-time run's within 12 mm (the
  // lag is 0.7 m/s × 0.1 s = 70 mm; moved on by it, the difference is 60 mm).
  EXPECT_NEAR(Mean(late.capture_error_m), Mean(on_time.capture_error_m), 0.012);
  // Crop records: each on-time crop's nearest late crop stands within 5 mm
  // along on average (the same plants, placed from the same views).
  double along = 0.0;
  int matched = 0;
  for (const treatment::PlantRecord& a : on_time.records) {
    if (!a.crop() || !a.confirmed()) continue;
    double best = 1e9;
    const treatment::PlantRecord* nearest = nullptr;
    for (const treatment::PlantRecord& b : late.records) {
      if (!b.crop() || !b.confirmed()) continue;
      const double d = (a.bed_m - b.bed_m).norm();
      if (d < best) best = d, nearest = &b;
    }
    if (nearest == nullptr || best > 0.15) continue;
    along += nearest->bed_m.y() - a.bed_m.y();
    ++matched;
  }
  ASSERT_GT(matched, 20);
  EXPECT_LT(std::abs(along / matched), 0.005) << "mean along shift of " << matched << " crops";
  // The bar still sprays: about as many open ticks as on time (±20 %).
  EXPECT_NEAR(late.open_ticks, on_time.open_ticks, 0.2 * on_time.open_ticks);
}

// The treatment map holds a window from 2 m behind the bar to the view's
// far edge, however long the pass: 20 m here, under 12 m of rows at most
// (the 5 m behind the start until the first step; then 2 m + the bar's
// 0.6 m + a 3.4 m step + the view), and the bar sprays on.
TEST(Pipeline, TreatmentMapKeepsAWindowAroundTheVehicle) {
  const Outcome run = Drive(20.0, 0);
  EXPECT_GT(run.first_row, 0);
  EXPECT_LT(run.max_window_rows, 12.0 / 0.01333);
  EXPECT_GT(run.open_ticks, 100);
}

// Feeds a pipeline the first `seconds` of a pass in time order; returns
// the simulator for more.
class PipelineFaults : public ::testing::Test {
 protected:
  PipelineFaults()
      : simulator_(Pass(20.0)),
        p_(simulator_.camera(), OptionsFor(Pass(20.0)),
           [this](int64_t, uint64_t mask) { last_mask_ = mask; }) {}

  // The next frame and its odometry, in order.
  const FrameResult& Next(bool with_odometry = true) {
    EXPECT_TRUE(simulator_.Next(frame_));
    if (!with_odometry) frame_.odometry.clear();
    const auto feed = [&](bool before) {
      for (const sim::OdometrySample& o : frame_.odometry) {
        if ((o.utime <= frame_.truth.utime) == before) ticks_ = p_.AddOdometry(Sample(o)).ticks;
      }
    };
    feed(true);
    const FrameResult& r = p_.ProcessFrame(frame_.truth.utime, frame_.truth.index,
                                           frame_.rendered.image);
    feed(false);
    return r;
  }
  void TrackFor(int frames) {
    for (int i = 0; i < frames; ++i) Next();
    ASSERT_EQ(p_.tracker().mode(), tracking::TrackerMode::kTracking);
  }
  // The reasons of the newest tick.
  uint32_t Reasons() const { return p_.last_tick() ? p_.last_tick()->fail_reasons : 0u; }
  static bool Has(const FrameResult& r, const std::string& text) {
    for (const std::string& f : r.faults) {
      if (f.find(text) != std::string::npos) return true;
    }
    return false;
  }

  sim::Simulator simulator_;
  Pipeline p_;
  sim::SimFrame frame_;
  std::span<const treatment::TickResult> ticks_;
  uint64_t last_mask_ = 0;
};

TEST_F(PipelineFaults, FrameOutOfTimeOrderIsRefusedAndClosesTheBarUntilTheNext) {
  TrackFor(60);
  const cv::Mat image = frame_.rendered.image.clone();
  const int64_t earlier = frame_.truth.utime - 40'000;
  const FrameResult& r = p_.ProcessFrame(earlier, 999, image);
  EXPECT_FALSE(r.accepted);
  EXPECT_TRUE(Has(r, "out of time order")) << r.faults.front();
  // The next odometry sample ticks with the camera at fault: all closed.
  ASSERT_TRUE(simulator_.Next(frame_));
  ASSERT_FALSE(frame_.odometry.empty());
  const PoseResult& pose = p_.AddOdometry(Sample(frame_.odometry.front()));
  ASSERT_FALSE(pose.ticks.empty());
  EXPECT_NE(pose.ticks.back().fail_reasons & treatment::kCameraLost, 0u);
  EXPECT_EQ(pose.ticks.back().open_mask, 0u);
  EXPECT_EQ(last_mask_, 0u);
  // A good frame clears it.
  const FrameResult& good = p_.ProcessFrame(frame_.truth.utime, frame_.truth.index,
                                            frame_.rendered.image);
  EXPECT_TRUE(good.accepted);
  for (size_t i = 1; i < frame_.odometry.size(); ++i) p_.AddOdometry(Sample(frame_.odometry[i]));
  EXPECT_EQ(Reasons() & treatment::kCameraLost, 0u);
}

TEST_F(PipelineFaults, FrameWithNoImageIsRefusedWithTheBarClosed) {
  TrackFor(60);
  ASSERT_TRUE(simulator_.Next(frame_));
  for (const sim::OdometrySample& o : frame_.odometry) {
    if (o.utime <= frame_.truth.utime) p_.AddOdometry(Sample(o));
  }
  const FrameResult& r = p_.ProcessFrame(frame_.truth.utime, frame_.truth.index, cv::Mat());
  EXPECT_FALSE(r.accepted);
  EXPECT_TRUE(Has(r, "has no image"));
  for (const sim::OdometrySample& o : frame_.odometry) {
    if (o.utime > frame_.truth.utime) p_.AddOdometry(Sample(o));
  }
  EXPECT_NE(Reasons() & treatment::kCameraLost, 0u);
  EXPECT_EQ(last_mask_, 0u);
  // The wrong size too.
  const FrameResult& small = p_.ProcessFrame(frame_.truth.utime + 80'000, 1000,
                                             cv::Mat(10, 10, CV_8UC1, cv::Scalar(0)));
  EXPECT_FALSE(small.accepted);
  EXPECT_TRUE(Has(small, "the calibration is"));
}

TEST_F(PipelineFaults, OdometryThatStopsClosesTheBarFromTheFrames) {
  TrackFor(60);
  // Frames keep coming, the wheels say nothing: within 0.2 s the frames
  // command the bar closed themselves (no odometry sample ticks it).
  const FrameResult* r = nullptr;
  for (int i = 0; i < 5; ++i) r = &Next(false);
  EXPECT_TRUE(r->accepted);
  EXPECT_TRUE(Has(*r, "odometry: stopped"));
  ASSERT_FALSE(r->ticks.empty());
  EXPECT_NE(r->ticks.back().fail_reasons & treatment::kOdometryInvalid, 0u);
  EXPECT_EQ(r->ticks.back().open_mask, 0u);
  EXPECT_EQ(last_mask_, 0u);
}

TEST_F(PipelineFaults, PipelineFedAfterItLostTheGridKeepsTheBarClosed) {
  TrackFor(60);
  // Blank frames for 4 s (beyond the tracker's 3 s of coasting): lost.
  const cv::Mat blank(frame_.rendered.image.size(), frame_.rendered.image.type(), cv::Scalar(0));
  int lost_at = -1;
  for (int i = 0; i < 60; ++i) {
    ASSERT_TRUE(simulator_.Next(frame_));
    for (const sim::OdometrySample& o : frame_.odometry) p_.AddOdometry(Sample(o));
    const FrameResult& r = p_.ProcessFrame(frame_.truth.utime, frame_.truth.index, blank);
    EXPECT_TRUE(r.accepted);
    if (r.mode == tracking::TrackerMode::kLost && lost_at < 0) {
      lost_at = i;
      EXPECT_TRUE(Has(r, "tracker:"));
    }
    if (lost_at >= 0) {
      EXPECT_EQ(last_mask_, 0u) << "frame " << i;
    }
  }
  ASSERT_GE(lost_at, 0);
  EXPECT_NE(Reasons() & treatment::kTrackerLost, 0u);
  // Fed on after the loss: frames are taken (the tracker tries to find the
  // grid again) and nothing throws; the bar stays closed until it does.
  for (int i = 0; i < 3; ++i) {
    const FrameResult& r = Next();
    EXPECT_TRUE(r.accepted);
    if (r.mode != tracking::TrackerMode::kTracking) {
      EXPECT_EQ(last_mask_, 0u);
    }
  }
}

// Frames that show no plant (a bare patch, a dirty lens) leave the tracker
// coasting on the wheels: the grid's covariance grows with every metre, and
// with it the ellipse of where the plants will stand at the bar. The bar
// closes on that (kPositionUncertain, with the reason) before the tracker
// gives the grid up, and opens again once frames update it.
TEST_F(PipelineFaults, CoastingClosesTheBarOnUncertaintyAndFramesReopenIt) {
  TrackFor(60);
  ASSERT_TRUE(p_.last_tick().has_value());
  EXPECT_EQ(Reasons() & treatment::kPositionUncertain, 0u) << "uncertain while tracking";
  const treatment::TreatmentSystem& system = *p_.treatment();
  const double margin_along = system.options().scheduler.fail_safe.max_reach_along_m;
  const treatment::PlantReach tracked = system.ReachAtBar(p_.tracker());
  EXPECT_LT(tracked.along_m, margin_along);
  const cv::Mat blank(frame_.rendered.image.size(), frame_.rendered.image.type(), cv::Scalar(0));
  int closed_at = -1;
  double last_reach = tracked.along_m;
  for (int i = 0; i < 40 && closed_at < 0; ++i) {
    ASSERT_TRUE(simulator_.Next(frame_));
    for (const sim::OdometrySample& o : frame_.odometry) p_.AddOdometry(Sample(o));
    const FrameResult& r = p_.ProcessFrame(frame_.truth.utime, frame_.truth.index, blank);
    ASSERT_TRUE(r.accepted);
    ASSERT_EQ(r.mode, tracking::TrackerMode::kTracking) << "lost before the bar closed, frame " << i;
    // Coasting: the grid's covariance grows with every metre; the plant at
    // the bar changes line as the vehicle moves (its lever arm on l̄ with
    // it), so the reach may dip by a few per cent from one frame to the next.
    const double reach = system.ReachAtBar(p_.tracker()).along_m;
    EXPECT_GE(reach, tracked.along_m) << "coasting: the reach grows from where tracking left it";
    EXPECT_GE(reach, 0.95 * last_reach) << "frame " << i;
    last_reach = std::max(last_reach, reach);
    if (Reasons() & treatment::kPositionUncertain) closed_at = i;
  }
  ASSERT_GE(closed_at, 0) << "reach " << last_reach << " m, margin " << margin_along << " m";
  EXPECT_EQ(last_mask_, 0u);
  EXPECT_EQ(p_.last_tick()->open_mask, 0u);
  ASSERT_FALSE(p_.last_tick()->messages.empty());
  EXPECT_NE(p_.last_tick()->messages.front().find("plant position uncertain at the bar"),
            std::string::npos)
      << p_.last_tick()->messages.front();
  // The bar closed while coasting, before the tracker's 3 s: 12.5 Hz frames.
  EXPECT_LT(closed_at * 0.08, p_.tracker().options().max_coast_s);
  // Plants again: the updates shrink the ellipse, the reason clears and the
  // bar sprays the crops it reaches.
  int cleared_at = -1, opened_at = -1;
  for (int i = 0; i < 60 && opened_at < 0; ++i) {
    const FrameResult& r = Next();
    ASSERT_TRUE(r.accepted);
    if (cleared_at < 0 && (Reasons() & treatment::kPositionUncertain) == 0) cleared_at = i;
    if (cleared_at >= 0 && last_mask_ != 0) opened_at = i;
  }
  ASSERT_GE(cleared_at, 0);
  RecordProperty("reach_along_tracking_mm", std::to_string(1e3 * tracked.along_m));
  RecordProperty("margin_along_mm", std::to_string(1e3 * margin_along));
  RecordProperty("closed_after_coasting_frames", closed_at + 1);
  RecordProperty("cleared_after_frames", cleared_at + 1);
  RecordProperty("opened_after_frames", opened_at + 1);
  EXPECT_LT(cleared_at, 5) << "frames until the ellipse fits again";
  EXPECT_GE(opened_at, 0) << "the bar never opened again";
  EXPECT_EQ(p_.tracker().mode(), tracking::TrackerMode::kTracking);
}

TEST(PipelineOptionsTest, InvalidOptionsNameTheirKey) {
  PipelineOptions o;
  o.max_odometry_age_s = 0.0;
  o.tracker.max_coast_s = -1.0;
  const OptionErrors e = o.Validate();
  ASSERT_GE(e.size(), 2u);
  bool age = false, coast = false;
  for (const OptionError& x : e) {
    age |= x.key == "max_odometry_age_s";
    coast |= x.key == "tracker.max_coast_s";
  }
  EXPECT_TRUE(age);
  EXPECT_TRUE(coast);
}

}  // namespace
}  // namespace plantscale::pipeline

namespace plantscale::pipeline {
namespace {

// The camera's motion as the second motion source: each bad frame makes it
// invalid with its reason, and the wheels carry on alone.
class PipelineVisualMotion : public ::testing::Test {
 protected:
  static PipelineOptions WithMotion() {
    const sim::SimulatorOptions so = Pass(20.0);
    PipelineOptions o = OptionsFor(so);
    o.motion.enabled = true;
    o.motion.visual = motion::VisualOdometryFor(so.field.crop_radius_m,
                                                so.field.crop_radius_m * so.field.crop_height_ratio);
    return o;
  }
  PipelineVisualMotion() : simulator_(Pass(20.0)), p_(simulator_.camera(), WithMotion()) {}

  // The next frame (its image changed by `spoil`) between its odometry.
  const FrameResult& Next(const std::function<void(cv::Mat&)>& spoil = {}) {
    EXPECT_TRUE(simulator_.Next(frame_));
    for (const sim::OdometrySample& o : frame_.odometry) {
      if (o.utime <= frame_.truth.utime) p_.AddOdometry(Sample(o));
    }
    if (spoil) spoil(frame_.rendered.image);
    const FrameResult& r = p_.ProcessFrame(frame_.truth.utime, frame_.truth.index,
                                           frame_.rendered.image);
    for (const sim::OdometrySample& o : frame_.odometry) {
      if (o.utime > frame_.truth.utime) p_.AddOdometry(Sample(o));
    }
    return r;
  }
  // A bad frame: the camera's motion is invalid, the next wheel samples are
  // the wheels' alone, and the grid keeps tracking.
  void ExpectWheelsCarryOn(const std::function<void(cv::Mat&)>& spoil) {
    for (int i = 0; i < 15; ++i) Next();
    ASSERT_EQ(p_.tracker().mode(), tracking::TrackerMode::kTracking);
    const FrameResult& r = Next(spoil);
    EXPECT_FALSE(r.visual.valid);
    EXPECT_FALSE(r.visual.reason.empty());
    EXPECT_EQ(p_.last_motion_source(), FusedSource::kWheels);
    EXPECT_EQ(p_.tracker().mode(), tracking::TrackerMode::kTracking);
  }

  sim::Simulator simulator_;
  Pipeline p_;
  sim::SimFrame frame_;
};

TEST_F(PipelineVisualMotion, GoodFramesGiveTheCameraSMotion) {
  int valid = 0;
  for (int i = 0; i < 20; ++i) {
    const FrameResult& r = Next();
    if (!r.visual.valid) continue;
    ++valid;
    EXPECT_NEAR(r.visual.speed_m_s, 0.7, 0.15) << "frame " << i;  // sim speed 0.7 m/s
  }
  EXPECT_GE(valid, 10);
}

TEST_F(PipelineVisualMotion, CoveredCameraIsInvalidAndTheWheelsCarryOn) {
  ExpectWheelsCarryOn([](cv::Mat& image) { image.setTo(cv::Scalar::all(0)); });
}

TEST_F(PipelineVisualMotion, BlurredFrameIsInvalidAndTheWheelsCarryOn) {
  ExpectWheelsCarryOn([](cv::Mat& image) { cv::GaussianBlur(image, image, cv::Size(0, 0), 12.0); });
}

TEST_F(PipelineVisualMotion, FrameOfAnotherPlaceIsInvalidAndTheWheelsCarryOn) {
  // All features new: the frame 4 m further on.
  sim::Simulator ahead(Pass(20.0));
  sim::SimFrame far;
  for (int i = 0; i < 75; ++i) ahead.Next(far);
  ExpectWheelsCarryOn([&](cv::Mat& image) { far.rendered.image.copyTo(image); });
}

}  // namespace
}  // namespace plantscale::pipeline

namespace plantscale::pipeline {
namespace {

// A learned model that does not load leaves the pipeline on the grid's
// rule: every frame says so in its faults, and the nozzles open exactly
// as they do with no model named.
TEST(PipelineLearned, AModelThatDoesNotLoadLeavesTheGridsRule) {
  const sim::SimulatorOptions so = Pass(6.0);
  int frames = 0;
  const auto run = [&](const LearnedOptions& learned, std::vector<std::string>& faults) {
    frames = 0;
    sim::Simulator simulator(so);
    std::vector<uint64_t> masks;
    PipelineOptions o = OptionsFor(so);
    o.learned = learned;
    Pipeline p(simulator.camera(), o, [&masks](int64_t, uint64_t mask) { masks.push_back(mask); });
    sim::SimFrame frame;
    std::vector<OdometrySample> odometry;
    while (simulator.Next(frame)) {
      odometry.clear();
      for (const sim::OdometrySample& s : frame.odometry) odometry.push_back(Sample(s));
      const FrameResult& r = p.Step(frame.truth.utime, frame.truth.index, frame.rendered.image, odometry);
      ++frames;
      EXPECT_TRUE(r.accepted);
      EXPECT_TRUE(r.classes.classes.empty());
      if (!r.faults.empty()) faults.push_back(r.faults.front());
    }
    EXPECT_FALSE(p.learned());
    return masks;
  };
  std::vector<std::string> none_faults, junk_faults, missing_faults;
  const std::vector<uint64_t> plain = run({}, none_faults);
  LearnedOptions junk;
  junk.onnx = std::make_shared<const std::vector<uint8_t>>(std::vector<uint8_t>{1, 2, 3, 4});
  junk.source = "crop.onnx";
  const std::vector<uint64_t> with_junk = run(junk, junk_faults);
  LearnedOptions missing;
  missing.source = "gone.onnx";
  missing.unreadable = "gone.onnx: no such file";
  const std::vector<uint64_t> with_missing = run(missing, missing_faults);
  EXPECT_EQ(with_junk, plain);
  EXPECT_EQ(with_missing, plain);
  ASSERT_FALSE(plain.empty());
  EXPECT_GT(std::count_if(plain.begin(), plain.end(), [](uint64_t m) { return m != 0; }), 10);
  ASSERT_FALSE(junk_faults.empty());
  EXPECT_EQ(static_cast<int>(junk_faults.size()), frames);  // every frame says so, first
  EXPECT_EQ(junk_faults.front().rfind("segmenter model crop.onnx: not loaded (", 0), 0u) << junk_faults.front();
  EXPECT_NE(junk_faults.front().find("crop and weed by the grid's rule"), std::string::npos);
  ASSERT_FALSE(missing_faults.empty());
  EXPECT_EQ(missing_faults.front(),
            "segmenter model gone.onnx: not loaded (gone.onnx: no such file); crop and weed by the grid's rule");
  for (const std::string& f : none_faults) EXPECT_EQ(f.find("segmenter model"), std::string::npos);
}

}  // namespace
}  // namespace plantscale::pipeline
