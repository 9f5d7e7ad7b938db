// The treatment chain's costs: classifying a frame's blobs against the
// predicted crop grid, adding a frame's footprints to the treatment map, and
// one 50 Hz scheduler tick of a 64-nozzle bar.
#include <benchmark/benchmark.h>

#include <random>
#include <vector>

#include "engine/classify/crop_classifier.h"
#include "engine/treatment/nozzle_scheduler.h"
#include "engine/treatment/treatment_map.h"

namespace plantscale::treatment {
namespace {

std::vector<classify::PredictedCrop> Grid() {
  std::vector<classify::PredictedCrop> crops;
  for (int m = 0; m < 5; ++m) {
    for (int n = -1; n <= 1; ++n) {
      classify::PredictedCrop c;
      c.m = m, c.n = n;
      c.ground_m = {0.475 * n, 1.0 + 0.45 * m};
      c.jacobian(0, 0) = 1.0;
      c.jacobian(1, 1) = 1.0;
      c.bounce_jacobian(1, 0) = 2.0;
      crops.push_back(c);
    }
  }
  return crops;
}

void BM_Classify(benchmark::State& state) {
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> x(-0.8, 0.8), y(0.8, 3.2), a(0.0005, 0.06);
  std::vector<tracking::Feature> features(static_cast<size_t>(state.range(0)));
  for (auto& f : features) f.ground_m = {x(rng), y(rng)}, f.area_m2 = a(rng);
  const std::vector<classify::PredictedCrop> crops = Grid();
  classify::CropClassifier classifier(classify::ClassifierOptions{});
  geometry::Matrix5d p = geometry::Matrix5d::Identity() * 1e-5;
  std::vector<classify::BlobDecision> out;
  for (auto _ : state) {
    classifier.Classify(features, crops, p, out);
    benchmark::DoNotOptimize(out.data());
  }
  state.SetItemsProcessed(state.iterations() * state.range(0));
}
BENCHMARK(BM_Classify)->Arg(20)->Arg(100);

void BM_MapFootprints(benchmark::State& state) {
  TreatmentMap map(TreatmentMapOptions{});
  const std::vector<classify::PredictedCrop> crops = Grid();
  double s = 0.0;
  for (auto _ : state) {
    for (const auto& c : crops) {  // 15 crop footprints of 0.13 m, as one frame
      const Eigen::Vector2d p = c.ground_m + Eigen::Vector2d(0.0, s);
      const Quad q = {p + Eigen::Vector2d(-0.065, -0.06), p + Eigen::Vector2d(0.065, -0.06),
                      p + Eigen::Vector2d(0.07, 0.06), p + Eigen::Vector2d(-0.07, 0.06)};
      benchmark::DoNotOptimize(map.AddFootprint(q, true));
    }
    s = s < 30.0 ? s + 0.056 : 0.0;
  }
}
BENCHMARK(BM_MapFootprints);

// The same frame when footprints follow their plants
// (TreatmentOptions::crop_footprint_follows_plant, TreatmentSystem's
// PlaceFollowing): each of the 15 plants, seen in `range(0)` frames before,
// takes back its earlier footprints' votes, adds this frame's footprint and
// puts them all down again 1 mm further along.
void BM_MapFootprintsFollowing(benchmark::State& state) {
  TreatmentMap map(TreatmentMapOptions{});
  const std::vector<classify::PredictedCrop> crops = Grid();
  const int seen = static_cast<int>(state.range(0));
  const auto quad = [](const Eigen::Vector2d& p) -> Quad {
    return {p + Eigen::Vector2d(-0.065, -0.06), p + Eigen::Vector2d(0.065, -0.06),
            p + Eigen::Vector2d(0.07, 0.06), p + Eigen::Vector2d(-0.07, 0.06)};
  };
  std::vector<std::vector<ColumnSpan>> spans(crops.size());
  std::vector<double> along(crops.size());
  for (size_t i = 0; i < crops.size(); ++i) {
    along[i] = crops[i].ground_m.y();
    for (int k = 0; k < seen; ++k) map.AppendSpans(quad(crops[i].ground_m), along[i], spans[i]);
    map.AddSpans(spans[i], along[i], 1, true);
  }
  for (auto _ : state) {
    for (size_t i = 0; i < crops.size(); ++i) {
      map.AddSpans(spans[i], along[i], -1, true);
      along[i] += 0.001;
      const size_t before = spans[i].size();
      map.AppendSpans(quad(Eigen::Vector2d(crops[i].ground_m.x(), along[i])), along[i], spans[i]);
      benchmark::DoNotOptimize(map.AddSpans(spans[i], along[i], 1, true));
      map.AddSpans(std::span<const ColumnSpan>(spans[i]).subspan(before), along[i], -1, true);
      spans[i].resize(before);  // back to `seen` footprints per plant
    }
  }
}
BENCHMARK(BM_MapFootprintsFollowing)->Arg(10)->Arg(40);

void BM_SchedulerTick(benchmark::State& state) {
  TreatmentMapOptions mo;
  mo.majority_threshold = 1;
  TreatmentMap map(mo);
  for (int m = 0; m < 60; ++m) {
    for (int n = -1; n <= 1; ++n) {
      const Eigen::Vector2d p(0.475 * n, 0.45 * m);
      map.AddFootprint({p + Eigen::Vector2d(-0.06, -0.06), p + Eigen::Vector2d(0.06, -0.06),
                        p + Eigen::Vector2d(0.06, 0.06), p + Eigen::Vector2d(-0.06, 0.06)},
                       true);
    }
  }
  NozzleScheduler scheduler(SchedulerOptions{});
  SafetyInputs safety;
  safety.tracking = true;
  BedPose pose;
  pose.speed_m_s = 0.7;
  int64_t utime = 0;
  for (auto _ : state) {
    utime += 20000;
    pose.utime = safety.pose_utime = safety.last_frame_utime = utime;
    pose.distance_m = pose.distance_m < 25.0 ? pose.distance_m + 0.014 : 1.0;
    const TickResult r = scheduler.Tick(utime, pose, map, safety);
    benchmark::DoNotOptimize(r.open_mask);
  }
}
BENCHMARK(BM_SchedulerTick);

}  // namespace
}  // namespace plantscale::treatment

BENCHMARK_MAIN();
