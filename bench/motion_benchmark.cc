// Correspondence + motion recovery speed (issue 7): one FeatureTracker
// update — search regions, two-way matches, Hough clustering, Umeyama,
// filtering, final matching, Kalman updates — with 50 features per frame in
// at most 1 ms. Feature extraction (segmentation, contours) is not counted.
// Also the ground's shift (the image prior without odometry) per frame.
// Run: build/bench/motion_benchmark
#include <benchmark/benchmark.h>

#include <map>
#include <memory>
#include <random>

#include <opencv2/imgproc.hpp>

#include "engine/geometry/test_cameras.h"
#include "engine/motion/feature_tracker.h"
#include "engine/motion/ground_shift.h"
#include "engine/motion/test_scenes.h"
#include "engine/motion/visual_odometry.h"

namespace plantscale::motion {
namespace {

// 60 frames of a scatter of ground features seen from a vehicle advancing
// 0.1 m per frame, ~50 features per frame with 1 mm noise.
const std::vector<std::vector<Feature>>& Frames(int per_frame) {
  static std::map<int, std::vector<std::vector<Feature>>> cache;
  auto& frames = cache[per_frame];
  if (!frames.empty()) return frames;
  const geometry::CameraModel camera(testing::SanchizPlaCamera());
  const auto points = testing::ScatterPoints(8.0, per_frame / 0.15, 5);
  std::mt19937 rng(9);
  VehiclePose2 pose;
  const PlanarMotion step{-0.0005, {0.0002, -0.1}};
  for (int k = 0; k < 60; ++k, pose = Compose(pose, step))
    frames.push_back(testing::Observe(points, pose, camera, 0.001, rng));
  return frames;
}

void BM_TrackerUpdate(benchmark::State& state) {
  const auto& frames = Frames(static_cast<int>(state.range(1)));
  const geometry::CameraModel camera(testing::SanchizPlaCamera());
  TrackerOptions o;
  o.method = state.range(0) == 0 ? MotionMethod::kPaper : MotionMethod::kOurs;
  o.initial_motion = {0.0, {0.0, -0.1}};
  size_t features = 0, locked = 0, updates = 0;
  auto tracker = std::make_unique<FeatureTracker>(o, camera, 0.0);
  size_t k = 0;
  for (auto _ : state) {
    if (k == frames.size()) {
      state.PauseTiming();
      tracker = std::make_unique<FeatureTracker>(o, camera, 0.0);
      k = 0;
      state.ResumeTiming();
    }
    const FrameMotion& m = tracker->Update(frames[k]);
    benchmark::DoNotOptimize(m.motion);
    features += frames[k].size();
    locked += m.locked ? 1 : 0;
    ++updates;
    ++k;
  }
  state.counters["features"] = static_cast<double>(features) / static_cast<double>(updates);
  state.counters["locked"] = static_cast<double>(locked) / static_cast<double>(updates);
  state.SetLabel(Name(o.method));
}
// Args: method (0 paper, 1 ours), features per frame.
BENCHMARK(BM_TrackerUpdate)->Args({0, 50})->Args({1, 50})->Args({1, 100})->Unit(benchmark::kMicrosecond);

// The pipeline's visual motion source per frame (issue 38): the tracker
// update searched around a prior (here the wheels reading 10 % fast, 1 cm
// over the frame: inside the default 15 mm prior gate), and
// the speed, turn rate and their σ.
void BM_VisualOdometry(benchmark::State& state) {
  const auto& frames = Frames(static_cast<int>(state.range(0)));
  const geometry::CameraModel camera(testing::SanchizPlaCamera());
  VisualOdometryOptions o;
  o.tracker.fit_row_heading = false;
  auto vo = std::make_unique<VisualOdometry>(camera, o);
  size_t k = 0, valid = 0, updates = 0;
  int64_t utime = 0;
  for (auto _ : state) {
    if (k == frames.size()) {
      state.PauseTiming();
      vo = std::make_unique<VisualOdometry>(camera, o);
      k = 0;
      state.ResumeTiming();
    }
    utime += 80000;  // 0.1 m per frame at 1.25 m/s
    const VisualMotion& m = vo->UpdateFeatures(utime, frames[k], 1.1 * 1.25, 0.0);
    benchmark::DoNotOptimize(m.speed_m_s);
    valid += m.valid ? 1 : 0;
    ++updates;
    ++k;
  }
  state.counters["valid"] = static_cast<double>(valid) / static_cast<double>(updates);
}
BENCHMARK(BM_VisualOdometry)->Arg(50)->Unit(benchmark::kMicrosecond);

// The ground's shift with no odometry (GroundShiftOptions::Soil()): a
// 640×480 frame of textured soil with plants cut out, warped onto the
// ground and phase-correlated with the previous one. Arg: the turn from
// the view's halves off (0) or on (1). Frames alternate between two views
// 6 px apart, so every update correlates a real shift.
void BM_GroundShift(benchmark::State& state) {
  const geometry::CameraModel camera(geometry::testing::ObliqueCamera());
  GroundShiftOptions o = GroundShiftOptions::Soil();
  o.measure_turn = state.range(0) != 0;
  GroundShiftEstimator estimator(o, camera);
  cv::Mat texture(camera.height() + 12, camera.width(), CV_8UC1);
  cv::randu(texture, 60, 140);
  cv::GaussianBlur(texture, texture, cv::Size(5, 5), 1.0);
  cv::Mat mask(camera.height(), camera.width(), CV_8UC1, cv::Scalar(0));
  for (int k = 0; k < 12; ++k)
    cv::circle(mask, {60 + 50 * k, 120 + 25 * (k % 3)}, 18, cv::Scalar(255), cv::FILLED);
  const cv::Mat frames[2] = {texture(cv::Rect(0, 0, camera.width(), camera.height())).clone(),
                             texture(cv::Rect(0, 6, camera.width(), camera.height())).clone()};
  size_t k = 0, valid = 0, turns = 0, updates = 0;
  for (auto _ : state) {
    const GroundShift g = estimator.Update(frames[k++ % 2], mask);
    benchmark::DoNotOptimize(g.t_m);
    valid += g.valid ? 1 : 0;
    turns += g.turn_valid ? 1 : 0;
    ++updates;
  }
  state.counters["valid"] = static_cast<double>(valid) / static_cast<double>(updates);
  state.counters["turn"] = static_cast<double>(turns) / static_cast<double>(updates);
}
BENCHMARK(BM_GroundShift)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace plantscale::motion

BENCHMARK_MAIN();
