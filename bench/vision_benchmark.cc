// Segmentation speed (issue 4): segmentation + blobs at 640×480 on one core
// in at most 0.5 ms per frame and at most 5× one cv::threshold pass over the
// same frame; both in this one run. Run: build/bench/vision_benchmark
#include <benchmark/benchmark.h>

#include <ctime>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "engine/geometry/test_cameras.h"
#include "engine/sim/simulator.h"
#include "engine/vision/segmenter.h"

namespace plantscale::vision {
namespace {

// A frame of 6-week crop with weeds, leaf shadows and plant shadows (like
// presets C and field) at 640×480.
const sim::RenderedFrame& Frame(sim::ImageKind kind) {
  static sim::RenderedFrame frames[2];
  sim::RenderedFrame& f = frames[kind == sim::ImageKind::kRgb ? 1 : 0];
  if (!f.image.empty()) return f;
  sim::SimulatorOptions o;
  o.camera = geometry::testing::ThesisCamera();
  o.field.crop_radius_m = 0.14;
  o.field.weed_density_per_m2 = 6.0;
  o.render.kind = kind;
  o.render.plant_shadow_depth = 0.2;
  o.render.leaf_shadow_fraction = 0.2;
  o.seed = 3;
  sim::Simulator simulator(o);
  sim::SimFrame frame;
  for (int i = 0; i < 30; ++i) simulator.Next(frame);
  f = frame.rendered;
  return f;
}

void SetUp() { cv::setNumThreads(1); }

void BM_CvThreshold(benchmark::State& state) {
  SetUp();
  const cv::Mat& grey = Frame(sim::ImageKind::kNir).image;
  cv::Mat mask;
  for (auto _ : state) {
    cv::threshold(grey, mask, 127, 255, cv::THRESH_BINARY);
    benchmark::DoNotOptimize(mask.data);
  }
}
BENCHMARK(BM_CvThreshold);

void Segment(benchmark::State& state, SegmenterOptions options, sim::ImageKind kind) {
  SetUp();
  const cv::Mat& image = Frame(kind).image;
  Segmenter segmenter(options);
  size_t blobs = 0;
  for (auto _ : state) {
    blobs = segmenter.Process(image).blobs.size();
    benchmark::DoNotOptimize(blobs);
  }
  state.counters["blobs"] = static_cast<double>(blobs);
}

SegmenterOptions With(ThresholdMethod method, double smoothing_px) {
  SegmenterOptions o;
  o.method = method;
  o.smoothing_px = smoothing_px;
  return o;
}

// The product's default: local soil level, smoothing, blobs.
void BM_SegmentNirDefault(benchmark::State& s) { Segment(s, {}, sim::ImageKind::kNir); }
BENCHMARK(BM_SegmentNirDefault);
// The default without growth into the blobs' hulls (hull_gain 0): what the
// growth and the second labelling for the tracker cost.
void BM_SegmentNirWithoutHullGrowth(benchmark::State& s) {
  SegmenterOptions o;
  o.hull_gain = 0.0;
  Segment(s, o, sim::ImageKind::kNir);
}
BENCHMARK(BM_SegmentNirWithoutHullGrowth);
// The default without growth into the soil (soil_growth.z 0).
void BM_SegmentNirWithoutSoilGrowth(benchmark::State& s) {
  SegmenterOptions o;
  o.soil_growth.z = 0.0;
  Segment(s, o, sim::ImageKind::kNir);
}
BENCHMARK(BM_SegmentNirWithoutSoilGrowth);
void BM_SegmentNirLocalUnsmoothed(benchmark::State& s) {
  Segment(s, With(ThresholdMethod::kLocal, 0.0), sim::ImageKind::kNir);
}
BENCHMARK(BM_SegmentNirLocalUnsmoothed);
// The thesis's adaptive interpolating threshold plus blobs (no hole
// filling or notch closing, as the thesis).
void BM_SegmentNirAdaptive(benchmark::State& s) {
  SegmenterOptions o = ThesisSegmenterOptions();
  o.smoothing_px = 0.0;
  Segment(s, o, sim::ImageKind::kNir);
}
BENCHMARK(BM_SegmentNirAdaptive);
void BM_SegmentRgbExgDefault(benchmark::State& s) { Segment(s, {}, sim::ImageKind::kRgb); }
BENCHMARK(BM_SegmentRgbExgDefault);

// The two targets in one measurement: the default segmentation +
// blobs and a cv::threshold pass over the same frame, alternated so that
// both see the same machine load, each timed in thread CPU time. Counters:
// segment_us and threshold_us per frame, and their ratio (target ≤ 5).
double ThreadCpuSeconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}
void BM_DefaultOverThreshold(benchmark::State& state, sim::ImageKind kind) {
  SetUp();
  const cv::Mat& image = Frame(kind).image;  // BGR for rgb: the threshold pass is over 3 channels
  Segmenter segmenter({});
  cv::Mat mask;
  constexpr int kThresholds = 16;  // cv::threshold is short: time a batch
  double segment_s = 0.0, threshold_s = 0.0;
  for (auto _ : state) {
    const double t0 = ThreadCpuSeconds();
    benchmark::DoNotOptimize(segmenter.Process(image).blobs.size());
    const double t1 = ThreadCpuSeconds();
    for (int k = 0; k < kThresholds; ++k) {
      cv::threshold(image, mask, 127, 255, cv::THRESH_BINARY);
      benchmark::DoNotOptimize(mask.data);
    }
    const double t2 = ThreadCpuSeconds();
    segment_s += t1 - t0;
    threshold_s += (t2 - t1) / kThresholds;
  }
  const auto n = static_cast<double>(state.iterations());
  state.counters["segment_us"] = 1e6 * segment_s / n;
  state.counters["threshold_us"] = 1e6 * threshold_s / n;
  state.counters["ratio"] = segment_s / threshold_s;
}
BENCHMARK_CAPTURE(BM_DefaultOverThreshold, nir, sim::ImageKind::kNir);
BENCHMARK_CAPTURE(BM_DefaultOverThreshold, rgb, sim::ImageKind::kRgb);

// Stages of the default NIR path, each on its own input.
const cv::Mat& SmoothedNir() {
  static cv::Mat smoothed;
  if (smoothed.empty()) {
    Segmenter segmenter({});
    smoothed = segmenter.Process(Frame(sim::ImageKind::kNir).image).plant_image.clone();
  }
  return smoothed;
}
void BM_StageCvGaussianBlurSigma2(benchmark::State& state) {
  SetUp();
  const cv::Mat& grey = Frame(sim::ImageKind::kNir).image;
  cv::Mat out;
  for (auto _ : state) {
    cv::GaussianBlur(grey, out, cv::Size(0, 0), 2.0);
    benchmark::DoNotOptimize(out.data);
  }
}
BENCHMARK(BM_StageCvGaussianBlurSigma2);
void BM_StageSmoothSigma2(benchmark::State& state) {
  SetUp();
  const cv::Mat& grey = Frame(sim::ImageKind::kNir).image;
  Smoother smoother(2.0);
  cv::Mat out;
  for (auto _ : state) {
    smoother.Apply(grey, out);
    benchmark::DoNotOptimize(out.data);
  }
}
BENCHMARK(BM_StageSmoothSigma2);
void BM_StageLocalThreshold(benchmark::State& state) {
  SetUp();
  const cv::Mat& grey = SmoothedNir();
  LocalThreshold local;
  cv::Mat mask;
  for (auto _ : state) {
    local.Apply(grey, mask);
    benchmark::DoNotOptimize(mask.data);
  }
}
BENCHMARK(BM_StageLocalThreshold);
void BM_StageBlobsOfDefaultMask(benchmark::State& state) {
  SetUp();
  Segmenter segmenter({});
  const cv::Mat mask = segmenter.Process(Frame(sim::ImageKind::kNir).image).mask.clone();
  BlobExtractor blobs;
  for (auto _ : state) benchmark::DoNotOptimize(blobs.Extract(mask).size());
}
BENCHMARK(BM_StageBlobsOfDefaultMask);
// A shape step (holes.h) on the thresholded default mask, without either
// shape step; the mask is restored outside the timing, so every pass has
// the same work. Counter: pixels the step changed.
template <typename Step>
void ShapeStep(benchmark::State& state, Step step) {
  SetUp();
  SegmenterOptions options;
  options.fill_holes_max_fraction = 0.0;
  options.close_notches_px = 0;
  options.hull_gain = 0.0;
  options.soil_growth.z = 0.0;
  Segmenter segmenter(options);
  const cv::Mat before = segmenter.Process(Frame(sim::ImageKind::kNir).image).mask.clone();
  cv::Mat mask = before.clone();
  int changed = 0;
  for (auto _ : state) {
    changed = step(mask);
    state.PauseTiming();
    before.copyTo(mask);
    state.ResumeTiming();
  }
  state.counters["changed_px"] = changed;
}
void BM_StageFillHolesOfDefaultMask(benchmark::State& state) {
  HoleFiller holes;
  ShapeStep(state, [&](cv::Mat& m) { return holes.Fill(m, 1536); });  // the default 0.5 %
}
BENCHMARK(BM_StageFillHolesOfDefaultMask);
void BM_StageCloseNotchesOfDefaultMask(benchmark::State& state) {
  NotchCloser notches;
  ShapeStep(state, [&](cv::Mat& m) { return notches.Close(m, 4); });
}
BENCHMARK(BM_StageCloseNotchesOfDefaultMask);
// Hull growth alone: the default mask before growth, and the low-gain mask
// (LocalThreshold::ApplyAtGain at the default hull_gain) made once.
void BM_StageGrowInHullsOfDefaultMask(benchmark::State& state) {
  SetUp();
  SegmenterOptions options;
  options.hull_gain = 0.0;
  options.soil_growth.z = 0.0;
  Segmenter segmenter(options);
  const cv::Mat before = segmenter.Process(Frame(sim::ImageKind::kNir).image).mask.clone();
  LocalThreshold local;
  cv::Mat high, low;
  local.Apply(SmoothedNir(), high);
  local.ApplyAtGain(SmoothedNir(), SegmenterOptions{}.hull_gain, low);
  HullGrower hull;
  cv::Mat mask = before.clone();
  int changed = 0;
  for (auto _ : state) {
    changed = hull.Grow(mask, low, SegmenterOptions{}.hull_min_area_px);
    state.PauseTiming();
    before.copyTo(mask);
    state.ResumeTiming();
  }
  state.counters["changed_px"] = changed;
}
BENCHMARK(BM_StageGrowInHullsOfDefaultMask);
// Soil growth alone (soil_growth.h), on the thresholded mask as above.
void BM_StageGrowIntoSoilOfDefaultMask(benchmark::State& state) {
  ShapeStep(state, [grower = SoilGrower(SegmenterOptions{}.soil_growth)](cv::Mat& m) mutable {
    return grower.Grow(Frame(sim::ImageKind::kNir).image, m);
  });
}
BENCHMARK(BM_StageGrowIntoSoilOfDefaultMask);

void BM_BlobsOnly(benchmark::State& state) {
  SetUp();
  cv::Mat mask;
  cv::threshold(Frame(sim::ImageKind::kNir).image, mask, 127, 255, cv::THRESH_BINARY);
  BlobExtractor blobs;
  for (auto _ : state) benchmark::DoNotOptimize(blobs.Extract(mask).size());
}
BENCHMARK(BM_BlobsOnly);

void BM_BlobsWithContours(benchmark::State& state) {
  SetUp();
  cv::Mat mask;
  cv::threshold(Frame(sim::ImageKind::kNir).image, mask, 127, 255, cv::THRESH_BINARY);
  BlobExtractor blobs({.min_area_px = 1, .trace_contours = true});
  for (auto _ : state) benchmark::DoNotOptimize(blobs.Extract(mask).size());
}
BENCHMARK(BM_BlobsWithContours);

}  // namespace
}  // namespace plantscale::vision

BENCHMARK_MAIN();
