// Correspondence + motion recovery speed (issue 7): one FeatureTracker
// update — search regions, two-way matches, Hough clustering, Umeyama,
// filtering, final matching, Kalman updates — with 50 features per frame in
// at most 1 ms. Feature extraction (segmentation, contours) is not counted.
// Run: build/bench/motion_benchmark
#include <benchmark/benchmark.h>

#include <map>
#include <memory>
#include <random>

#include "engine/motion/feature_tracker.h"
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

}  // namespace
}  // namespace plantscale::motion

BENCHMARK_MAIN();
