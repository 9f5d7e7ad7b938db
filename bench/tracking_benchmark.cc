// The grid tracker's cost per frame (issue 5: ≤ 0.2 ms): four 50 Hz
// odometry predictions and one vision update with the features of the
// thesis camera's view of a three-row bed, plus weeds.
#include <benchmark/benchmark.h>

#include "engine/tracking/grid_tracker.h"
#include "engine/tracking/test_scene.h"

namespace plantscale::tracking {
namespace {

void RunTracker(benchmark::State& state, TrackerOptions options) {
  testing::TestScene scene;
  scene.weeds_per_frame = static_cast<int>(state.range(0));
  GridTracker tracker(scene.camera, options);
  const geometry::Matrix5d p0 = geometry::Matrix5d::Identity() * 1e-4;
  scene.Drive({0.056, 0.056});
  const geometry::GridState start = scene.truth;  // the state at frames[0]
  tracker.Initialise(0, start, p0);
  // Frames prepared up front so that only the tracker is timed.
  std::vector<std::vector<Feature>> frames;
  for (int f = 0; f < 200; ++f) {
    frames.push_back(scene.Features());
    scene.Drive({0.056, 0.056});
  }
  int64_t utime = 0;
  size_t i = 1;
  tracker.ProcessFrame(0, 640, 480, frames[0]);
  int matched = 0;
  for (auto _ : state) {
    for (int k = 0; k < 4; ++k) {
      utime += 20000;
      tracker.AddOdometry(utime, 0.7, 0.7);
    }
    const FrameReport r = tracker.ProcessFrame(utime, 640, 480, frames[i]);
    matched = r.matched;
    benchmark::DoNotOptimize(r);
    if (++i == frames.size()) {
      state.PauseTiming();
      i = 1;
      tracker.Reset();
      tracker.Initialise(utime, start, p0);
      tracker.ProcessFrame(utime, 640, 480, frames[0]);
      state.ResumeTiming();
    }
  }
  state.counters["features"] = static_cast<double>(frames[0].size());
  state.counters["matched"] = matched;
}

// As evaluate tracking runs it on the field: centroids on the crop's
// heights, lasting camera bounce (plus, by default, the wheel scale, each
// plant's offset and centroid height).
void BM_TrackerFrameOurs(benchmark::State& state) {
  TrackerOptions o;
  o.crop_radius_m = 0.14;
  o.crop_height_m = 0.112;
  o.camera_bounce_correlation_s = 0.25;
  RunTracker(state, o);
}

void BM_TrackerFrameThesis(benchmark::State& state) {
  TrackerOptions o;
  o.estimate_spacing = false;
  o.plant_offsets = false;
  o.model_bounce = false;
  o.skip_merged_features = false;
  o.space = ObservationSpace::kImage;
  RunTracker(state, o);
}

BENCHMARK(BM_TrackerFrameOurs)->Arg(0)->Arg(20)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_TrackerFrameThesis)->Arg(0)->Arg(20)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace plantscale::tracking

BENCHMARK_MAIN();
