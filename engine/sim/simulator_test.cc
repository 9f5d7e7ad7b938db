#include "engine/geometry/test_cameras.h"
#include "engine/sim/simulator.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "engine/geometry/grid_model.h"

namespace plantscale::sim {
namespace {

bool HasKey(const OptionErrors& errors, const std::string& key) {
  return std::any_of(errors.begin(), errors.end(),
                     [&](const OptionError& e) { return e.key == key; });
}

// The thesis vehicle camera (config/cameras/thesis.yaml) over a short pass.
SimulatorOptions ShortPass() {
  SimulatorOptions o;
  o.preset = "unit-test";
  o.camera = geometry::testing::ThesisCamera();
  o.camera.virtual_plane_height_m = 0.0;
  o.length_m = 2.0;
  o.seed = 5;
  return o;
}

// The same view at 160×120 (a quarter of the focal length and of the pixel
// count per side), for tests about timing and odometry rather than images.
SimulatorOptions SmallImages(SimulatorOptions o) {
  o.camera.focal_length_m = 0.0012;
  o.camera.image_width_px = 160;
  o.camera.image_height_px = 120;
  return o;
}

std::vector<SimFrame> RunAll(const SimulatorOptions& options) {
  Simulator simulator(options);
  std::vector<SimFrame> frames;
  SimFrame frame;
  while (simulator.Next(frame)) {
    frames.push_back(frame);
    // Deep copies: the renderer reuses the frame's buffers for the next one.
    SimFrame& f = frames.back();
    f.rendered.image = frame.rendered.image.clone();
    f.rendered.labels = frame.rendered.labels.clone();
    f.rendered.instances = frame.rendered.instances.clone();
  }
  return frames;
}

TEST(Simulator, FramesAdvanceAtFrameRateWithoutJitter) {
  SimulatorOptions o = SmallImages(ShortPass());
  o.vehicle.frame_jitter_s = 0.0;
  Simulator simulator(o);
  SimFrame frame;
  int64_t previous = 0;
  int count = 0;
  while (simulator.Next(frame)) {
    EXPECT_EQ(frame.truth.index, count);
    // 1/12.5 Hz = 80 ms exactly, from utime 0.
    EXPECT_EQ(frame.truth.utime - previous, 80000) << "frame " << count;
    previous = frame.truth.utime;
    // Four 50 Hz odometry samples per frame, the last at the capture time.
    ASSERT_EQ(frame.odometry.size(), 4U) << "frame " << count;
    EXPECT_EQ(frame.odometry.back().utime, frame.truth.utime);
    ++count;
  }
  // 2 m at 0.7 m/s and 12.5 Hz: 35.7 frames due; the pass ends on the first
  // frame at or past 2 m.
  EXPECT_EQ(simulator.expected_frames(), 35);
  EXPECT_GE(count, simulator.expected_frames());
  EXPECT_LE(count, simulator.expected_frames() + 1);
  EXPECT_EQ(simulator.dropped_frames(), 0);
  EXPECT_FALSE(simulator.Next(frame));  // stays finished
}

TEST(Simulator, FrameTimesJitterAroundTheFramePeriod) {
  SimulatorOptions o = SmallImages(ShortPass());
  o.vehicle.frame_jitter_s = 0.002;
  const std::vector<SimFrame> frames = RunAll(o);
  ASSERT_GE(frames.size(), 30U);
  double sum = 0.0;
  bool any_jitter = false;
  for (size_t i = 1; i < frames.size(); ++i) {
    const double period_us = static_cast<double>(frames[i].truth.utime - frames[i - 1].truth.utime);
    // Difference of two N(0, 2 ms) capture errors: sd 2.8 ms; 6 sds = 17 ms.
    EXPECT_NEAR(period_us, 1e6 / 12.5, 6.0 * std::sqrt(2.0) * 2000.0) << "frame " << i;
    any_jitter = any_jitter || std::abs(period_us - 80000.0) > 1.0;
    sum += period_us;
  }
  EXPECT_TRUE(any_jitter);
  // The mean period telescopes: (last − first)/(n − 1), error ≤ 2·6·2 ms/(n − 1).
  EXPECT_NEAR(sum / static_cast<double>(frames.size() - 1), 80000.0,
              12.0 * 2000.0 / static_cast<double>(frames.size() - 1));
  for (size_t i = 0; i < frames.size(); ++i) {
    const SimFrame& f = frames[i];
    // 3 to 5 odometry samples (4 ± the jitter), the last at or after the
    // capture, the one before it earlier; and 20 ms apart.
    ASSERT_GE(f.odometry.size(), 3U);
    ASSERT_LE(f.odometry.size(), 5U);
    EXPECT_GE(f.odometry.back().utime, f.truth.utime);
    EXPECT_LT(f.odometry[f.odometry.size() - 2].utime, f.truth.utime);
    for (size_t k = 1; k < f.odometry.size(); ++k) {
      EXPECT_EQ(f.odometry[k].utime - f.odometry[k - 1].utime, 20000);
    }
    // Contiguous across frames: no sample lost or repeated.
    if (i > 0) {
      EXPECT_EQ(f.odometry.front().utime - frames[i - 1].odometry.back().utime, 20000);
    }
  }
}

TEST(Simulator, TruthPoseIsThePoseAtTheCaptureTime) {
  // Straight at constant speed (no zig-zag, wander or odometry errors), the
  // pose at capture time t is (x0, v·t); captures fall between odometry
  // steps, so this checks the interpolation of the pose (1e-9 m).
  SimulatorOptions o = SmallImages(ShortPass());
  o.vehicle.frame_jitter_s = 0.004;
  o.vehicle.zigzag_amplitude_m = 0.0;
  o.vehicle.heading_wander_sd_rad = 0.0;
  o.vehicle.start_offset_m = 0.07;
  Simulator simulator(o);
  SimFrame frame;
  int off_step = 0;
  while (simulator.Next(frame)) {
    const FrameTruth& t = frame.truth;
    EXPECT_NEAR(t.pose.y_m, 0.7 * static_cast<double>(t.utime) * 1e-6, 1e-9) << t.index;
    EXPECT_NEAR(t.pose.x_m, 0.07, 1e-12);
    EXPECT_NEAR(t.pose.heading_rad, 0.0, 1e-12);
    EXPECT_NEAR(t.grid.offset_m, -0.07, 1e-12);  // the central row is 7 cm to the left
    if (t.utime % 20000 != 0) ++off_step;
  }
  EXPECT_GT(off_step, 20);  // most captures fall between odometry samples
}

TEST(Simulator, OdometrySamplesPerFrameAverageFour) {
  SimulatorOptions o = SmallImages(ShortPass());
  o.vehicle.frame_jitter_s = 0.004;
  const std::vector<SimFrame> frames = RunAll(o);
  size_t samples = 0;
  for (const SimFrame& f : frames) samples += f.odometry.size();
  // 50 Hz / 12.5 Hz = 4. The total is fixed by the last capture time (to a
  // sample or two), so over ≈ 36 frames the mean is 4 ± 0.06; accept ±0.1.
  EXPECT_NEAR(static_cast<double>(samples) / static_cast<double>(frames.size()), 4.0, 0.1);
  // And all of them: one per 20 ms up to the last one.
  EXPECT_EQ(static_cast<int64_t>(samples) * 20000, frames.back().odometry.back().utime);
}

TEST(Simulator, DrivesTheWholeLength) {
  SimulatorOptions o = SmallImages(ShortPass());
  const std::vector<SimFrame> frames = RunAll(o);
  ASSERT_FALSE(frames.empty());
  double previous = 0.0;
  for (const SimFrame& f : frames) {
    EXPECT_GT(f.truth.distance_m, previous);
    previous = f.truth.distance_m;
    // Nearly straight along the bed: forward progress ≤ distance, and within
    // 1 % of it (a 3 cm zig-zag over 8 m barely lengthens the path).
    EXPECT_LE(f.truth.pose.y_m, f.truth.distance_m + 1e-9);
    EXPECT_GT(f.truth.pose.y_m, 0.99 * f.truth.distance_m - 0.03);
  }
  // The pass stops at the first frame at or beyond 2 m, at most one frame
  // period (56 mm at 0.7 m/s, + 6 jitter sds of 2 ms) + one odometry step
  // (14 mm) past it.
  EXPECT_GE(frames.back().truth.distance_m, 2.0);
  EXPECT_LE(frames.back().truth.distance_m, 2.0 + 0.7 * (0.08 + 0.012) + 0.014);
}

TEST(Simulator, GridTruthAgreesWithThePlantedPlants) {
  SimulatorOptions o = ShortPass();
  o.field.spacing_drift_fraction = 0.0;
  o.field.planting_jitter_m = 0.004;
  o.vehicle.zigzag_amplitude_m = 0.05;
  o.vehicle.start_offset_m = 0.04;
  o.vehicle.heading_wander_sd_rad = 0.01;
  o.vehicle.bump_pitch_sd_rad = 0.0;  // nominal camera, so root_px can be checked
  o.vehicle.bump_roll_sd_rad = 0.0;
  o.vehicle.bump_height_sd_m = 0.0;
  o.length_m = 3.0;
  Simulator simulator(o);
  const geometry::GridModel model(simulator.camera(), o.grid);
  const double sd = o.field.planting_jitter_m;
  SimFrame frame;
  int checked = 0;
  int frames = 0;
  int max_m = 0;
  while (simulator.Next(frame)) {
    ++frames;
    const FrameTruth& t = frame.truth;
    ASSERT_GE(t.line0, 0) << "frame " << t.index;
    const geometry::GridState& g = t.grid;
    EXPECT_NEAR(g.row_spacing_m, 0.475, 1e-12);
    EXPECT_NEAR(g.plant_spacing_m, 0.45, 1e-9);
    EXPECT_NEAR(g.bearing_rad, t.pose.heading_rad, 1e-12);
    // Line 0 is the bottom-most line in view (thesis §4.1.3): no shift needed.
    geometry::GridState shifted = g;
    EXPECT_EQ(model.ShiftReference(shifted), 0) << "frame " << t.index;
    for (const PlantTruth& p : t.plants) {
      // Vehicle position from the pose (docs/design.md §3), to 1e-12 m.
      const double c = std::cos(t.pose.heading_rad);
      const double s = std::sin(t.pose.heading_rad);
      const Eigen::Vector2d d = p.field_m - Eigen::Vector2d(t.pose.x_m, t.pose.y_m);
      EXPECT_NEAR(p.vehicle_m.x(), c * d.x() + s * d.y(), 1e-12);
      EXPECT_NEAR(p.vehicle_m.y(), -s * d.x() + c * d.y(), 1e-12);
      const Plant& plant = simulator.field().plants()[static_cast<size_t>(p.plant_id)];
      EXPECT_EQ(plant.position_m, p.field_m);
      EXPECT_EQ(plant.cls, p.cls);
      EXPECT_GT(p.area_px, 0);
      ASSERT_TRUE(p.root_px.has_value());
      const auto root = simulator.camera().Project({p.vehicle_m.x(), p.vehicle_m.y(), 0.0});
      ASSERT_TRUE(root.has_value());
      EXPECT_NEAR((*p.root_px - *root).norm(), 0.0, 1e-9);
      if (p.cls != PlantClass::kCrop) continue;
      // The grid model's position of crop (m, n) is the planted position up
      // to the planting jitter: within 6 sds of the 2-D error (p ≈ 1.5e-8).
      const int m = p.line - t.line0;
      const Eigen::Vector2d predicted = geometry::PlantInVehicle(g, m, p.row);
      EXPECT_LT((predicted - p.vehicle_m).norm(), 6.0 * sd)
          << "frame " << t.index << " m " << m << " n " << p.row;
      max_m = std::max(max_m, m);
      ++checked;
    }
  }
  EXPECT_GT(frames, 40);
  EXPECT_GT(checked, 40 * 6);  // ≈ 3 rows × 5–7 lines in view, less occlusion
  EXPECT_GE(max_m, 4);         // several lines ahead of line 0 were checked
}

TEST(Simulator, TruthMatchesTheRenderedInstances) {
  const std::vector<SimFrame> frames = RunAll(ShortPass());
  ASSERT_GE(frames.size(), 10U);
  for (size_t i = 0; i < frames.size(); i += 7) {
    const SimFrame& f = frames[i];
    std::vector<int> counts(f.rendered.plants.size() + 1, 0);
    for (int v = 0; v < f.rendered.instances.rows; ++v) {
      for (int u = 0; u < f.rendered.instances.cols; ++u) {
        ++counts[f.rendered.instances.at<uint16_t>(v, u)];
      }
    }
    ASSERT_FALSE(f.truth.plants.empty());
    for (const PlantTruth& p : f.truth.plants) {
      ASSERT_GE(p.instance, 1);
      ASSERT_LT(static_cast<size_t>(p.instance), counts.size());
      EXPECT_EQ(p.area_px, counts[static_cast<size_t>(p.instance)]);
      EXPECT_EQ(f.rendered.plants[static_cast<size_t>(p.instance - 1)].plant_index, p.plant_id);
    }
  }
}

void ExpectSameFrames(const std::vector<SimFrame>& a, const std::vector<SimFrame>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(cv::norm(a[i].rendered.image, b[i].rendered.image, cv::NORM_INF), 0.0) << i;
    EXPECT_EQ(cv::norm(a[i].rendered.labels, b[i].rendered.labels, cv::NORM_INF), 0.0) << i;
    EXPECT_EQ(cv::norm(a[i].rendered.instances, b[i].rendered.instances, cv::NORM_INF), 0.0) << i;
    const FrameTruth& ta = a[i].truth;
    const FrameTruth& tb = b[i].truth;
    EXPECT_EQ(ta.utime, tb.utime);
    EXPECT_EQ(ta.pose.x_m, tb.pose.x_m);
    EXPECT_EQ(ta.pose.y_m, tb.pose.y_m);
    EXPECT_EQ(ta.pose.heading_rad, tb.pose.heading_rad);
    EXPECT_EQ(ta.bounce.pitch_rad, tb.bounce.pitch_rad);
    EXPECT_EQ(ta.grid.AsVector(), tb.grid.AsVector());
    EXPECT_EQ(ta.line0, tb.line0);
    ASSERT_EQ(ta.plants.size(), tb.plants.size());
    for (size_t k = 0; k < ta.plants.size(); ++k) {
      EXPECT_EQ(ta.plants[k].plant_id, tb.plants[k].plant_id);
      EXPECT_EQ(ta.plants[k].area_px, tb.plants[k].area_px);
      EXPECT_EQ(ta.plants[k].centroid_px, tb.plants[k].centroid_px);
    }
    ASSERT_EQ(a[i].odometry.size(), b[i].odometry.size());
    for (size_t k = 0; k < a[i].odometry.size(); ++k) {
      EXPECT_EQ(a[i].odometry[k].left_m_s, b[i].odometry[k].left_m_s);
      EXPECT_EQ(a[i].odometry[k].right_m_s, b[i].odometry[k].right_m_s);
    }
  }
}

TEST(Simulator, SameSeedSameBytesDifferentSeedDifferentRun) {
  SimulatorOptions o = ShortPass();
  o.length_m = 1.0;
  o.render.plant_shadow_depth = 0.2;
  o.field.fractured_fraction = 0.2;
  const std::vector<SimFrame> a = RunAll(o);
  const std::vector<SimFrame> b = RunAll(o);
  ASSERT_GE(a.size(), 15U);
  ExpectSameFrames(a, b);
  o.seed = 6;
  const std::vector<SimFrame> c = RunAll(o);
  const size_t n = std::min(a.size(), c.size());
  ASSERT_GE(n, 15U);
  int different_images = 0;
  int different_poses = 0;
  for (size_t i = 0; i < n; ++i) {
    // Mean absolute difference per pixel above 1 grey level (another field
    // and texture give tens of levels).
    const double mean_abs = cv::norm(a[i].rendered.image, c[i].rendered.image, cv::NORM_L1) /
                            static_cast<double>(a[i].rendered.image.total());
    if (mean_abs > 1.0) ++different_images;
    if (a[i].truth.pose.x_m != c[i].truth.pose.x_m) ++different_poses;
  }
  EXPECT_EQ(different_images, static_cast<int>(n));
  EXPECT_GT(different_poses, static_cast<int>(n) / 2);
}

// A small, slow pass: many frames due, each cheap to render.
SimulatorOptions ManySmallFrames() {
  SimulatorOptions o = SmallImages(ShortPass());
  o.vehicle.speed_m_s = 0.1;
  o.vehicle.frame_jitter_s = 0.0;
  o.length_m = 3.0;  // 375 frames due
  return o;
}

TEST(Simulator, DropsAboutTheDroppedFrameFraction) {
  SimulatorOptions o = ManySmallFrames();
  o.vehicle.dropped_frame_fraction = 0.3;
  Simulator simulator(o);
  SimFrame frame;
  int emitted = 0;
  int gaps = 0;
  int64_t previous = 0;
  double distance = 0.0;
  while (simulator.Next(frame)) {
    ++emitted;
    const int64_t period = frame.truth.utime - previous;
    // Captures fall on the 80 ms clock; a gap of k periods drops k − 1 frames.
    ASSERT_EQ(period % 80000, 0);
    gaps += static_cast<int>(period / 80000) - 1;
    previous = frame.truth.utime;
    distance = frame.truth.distance_m;
  }
  const int due = emitted + simulator.dropped_frames();
  EXPECT_NEAR(due, 375, 2);
  // Dropped frames inside the pass show as gaps; those after the last
  // delivered frame do not.
  EXPECT_LE(gaps, simulator.dropped_frames());
  EXPECT_GE(gaps, simulator.dropped_frames() - 5);  // as above: ≤ 5 dropped at the end
  // Binomial sd √(375·0.3·0.7)/375 = 0.024; ±0.08 is 3.4 sds.
  EXPECT_NEAR(static_cast<double>(simulator.dropped_frames()) / due, 0.3, 0.08);
  // Still drives the whole pass: the last delivered frame is at most a few
  // dropped frames (8 mm each) short of 3 m (5 in a row: p = 0.3⁵ = 0.2 %).
  EXPECT_GE(distance, 3.0 - 5 * 0.008);
}

// The odometry of a dropped frame carries over to the next delivered frame
// (Simulator::Next), so dead reckoning over delivered frames loses nothing.
TEST(Simulator, OdometryOfDroppedFramesCarriesOver) {
  SimulatorOptions o = ManySmallFrames();
  o.length_m = 1.0;  // 125 frames due
  o.vehicle.dropped_frame_fraction = 0.3;
  Simulator simulator(o);
  SimFrame frame;
  int64_t last_sample = 0;
  while (simulator.Next(frame)) {
    ASSERT_FALSE(frame.odometry.empty());
    // Every 20 ms sample since the previous delivered frame is delivered.
    EXPECT_EQ(frame.odometry.front().utime - last_sample, 20000) << "frame " << frame.truth.index;
    EXPECT_EQ(static_cast<int64_t>(frame.odometry.size()) * 20000,
              frame.odometry.back().utime - last_sample);
    last_sample = frame.odometry.back().utime;
  }
  EXPECT_GT(simulator.dropped_frames(), 10);
}

TEST(Simulator, ValidatePrefixesKeysWithTheSection) {
  EXPECT_TRUE(ShortPass().Validate().empty());
  SimulatorOptions o = ShortPass();
  o.camera.height_m = -1.5;
  o.camera.tilt_rad = 95.0 * std::numbers::pi / 180.0;
  OptionErrors errors = o.Validate();
  EXPECT_TRUE(HasKey(errors, "camera.height_m"));
  EXPECT_TRUE(HasKey(errors, "camera.tilt_rad"));
  EXPECT_EQ(errors.size(), 2U);
  try {
    const Simulator simulator(o);
    ADD_FAILURE() << "Simulator accepted a camera below the ground";
  } catch (const InvalidOptionsError& e) {
    EXPECT_TRUE(HasKey(e.errors(), "camera.height_m"));
    EXPECT_TRUE(HasKey(e.errors(), "camera.tilt_rad"));
    const std::string what = e.what();
    EXPECT_NE(what.find("camera.height_m"), std::string::npos) << what;
    EXPECT_NE(what.find("camera.tilt_rad"), std::string::npos) << what;
    EXPECT_NE(what.find("unit-test"), std::string::npos) << what;  // the preset
  }
  SimulatorOptions other = ShortPass();
  other.field.rows = 2;
  other.vehicle.speed_m_s = -1.0;
  other.render.ray_samples = 0;
  other.grid.rows_each_side = -1;
  other.length_m = 0.0;
  errors = other.Validate();
  EXPECT_TRUE(HasKey(errors, "field.rows"));
  EXPECT_TRUE(HasKey(errors, "vehicle.speed_m_s"));
  EXPECT_TRUE(HasKey(errors, "render.ray_samples"));
  EXPECT_TRUE(HasKey(errors, "grid.rows_each_side"));
  EXPECT_TRUE(HasKey(errors, "length_m"));
  EXPECT_EQ(errors.size(), 5U);
}

}  // namespace
}  // namespace plantscale::sim
