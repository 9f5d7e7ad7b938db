// Crop-row detection speed (issue 11): a photograph's whole detect-rows
// pipeline after decoding (segmentation as `plantscale segment --method
// auto`, then the row detector with its curves) on one core, at most 5 ms
// per 320×240, 15 ms per 640×480 and 20 ms per 512×512 (issue 34); the
// detector alone on the plant mask; the curve fit alone.
// Run: build/bench/rows_benchmark
#include <benchmark/benchmark.h>

#include <numbers>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "engine/geometry/test_cameras.h"
#include "engine/rows/comb.h"
#include "engine/rows/row_detector.h"
#include "engine/sim/simulator.h"
#include "evaluation/rows_eval.h"

namespace plantscale::rows {
namespace {

// A low, perspective colour view (horizon in view) of 6-week crop with
// weeds and shadows, at 640×480 and scaled to `width`.
cv::Mat Photo(int width) {
  static cv::Mat full;
  if (full.empty()) {
    sim::SimulatorOptions o;
    o.camera = geometry::testing::ThesisCamera();
    o.camera.tilt_rad = 12.0 * std::numbers::pi / 180.0;
    o.field.crop_radius_m = 0.14;
    o.field.weed_density_per_m2 = 6.0;
    o.render.kind = sim::ImageKind::kRgb;
    o.render.plant_shadow_depth = 0.2;
    o.render.leaf_shadow_fraction = 0.2;
    o.seed = 3;
    sim::Simulator simulator(o);
    sim::SimFrame frame;
    for (int i = 0; i < 30; ++i) simulator.Next(frame);
    full = frame.rendered.image.clone();
  }
  if (width == full.cols) return full;
  cv::Mat small;
  cv::resize(full, small, cv::Size(width, width * full.rows / full.cols), 0, 0, cv::INTER_AREA);
  return small;
}

void BM_DetectRowsInPhoto(benchmark::State& state) {
  cv::setNumThreads(1);
  const cv::Mat photo = Photo(static_cast<int>(state.range(0)));
  RowDetector detector{RowDetectorOptions{}};
  double rows = 0;
  for (auto _ : state) {
    const RowDetection det = app::DetectRowsInPhoto(photo, detector);
    rows = static_cast<double>(det.rows.size());
    benchmark::DoNotOptimize(det.spacing_px);
  }
  state.counters["rows"] = rows;
}
BENCHMARK(BM_DetectRowsInPhoto)->Arg(320)->Arg(640)->Unit(benchmark::kMillisecond);

// Issue 34: the whole pipeline on a square 512×512 photograph (as the
// crop-row datasets store them), at most 20 ms, curves included.
void BM_DetectRowsInSquarePhoto(benchmark::State& state) {
  cv::setNumThreads(1);
  const int side = static_cast<int>(state.range(0));
  cv::Mat photo;
  cv::resize(Photo(640), photo, cv::Size(side, side), 0, 0, cv::INTER_AREA);
  RowDetector detector{RowDetectorOptions{}};
  double curved = 0;
  for (auto _ : state) {
    const RowDetection det = app::DetectRowsInPhoto(photo, detector);
    curved = det.curve.empty() ? 0.0 : 1.0;
    benchmark::DoNotOptimize(det.spacing_px);
  }
  state.counters["curved"] = curved;
}
BENCHMARK(BM_DetectRowsInSquarePhoto)->Arg(512)->Unit(benchmark::kMillisecond);

// The curve fit alone (curve_fit.h) on the plant fraction of a 512×512
// photograph's mask, with the straight model's geometry as prior.
void BM_CurveFit(benchmark::State& state) {
  cv::setNumThreads(1);
  cv::Mat mask(512, 512, CV_8UC1, cv::Scalar(0));
  for (int n = -3; n <= 3; ++n) {
    for (int v = 0; v < 512; v += 6) {
      const double t = (511.5 - v) / 512.0;
      const double u = 256.0 + 40.0 * t * t + n * 90.0 * (1.0 - 0.5 * t);
      cv::circle(mask, cv::Point(static_cast<int>(u), v), 5, cv::Scalar(255), cv::FILLED);
    }
  }
  cv::Mat unit;
  cv::resize(mask, unit, cv::Size(320, 320), 0, 0, cv::INTER_AREA);
  unit.convertTo(unit, CV_32F, 1.0 / 255.0);
  CurveFitter fitter{CurveFitOptions{}};
  const CurvePrior prior{true, 256.0, 90.0, 0.5 / 512.0, 0.5 / 512.0 * 256.0};
  for (auto _ : state) {
    const CurveFit fit = fitter.Fit(unit, 1.6, 1.6, 512.0, 512.0, prior);
    benchmark::DoNotOptimize(fit.coherence);
  }
}
BENCHMARK(BM_CurveFit)->Unit(benchmark::kMillisecond);

void BM_RowDetectorOnMask(benchmark::State& state) {
  cv::setNumThreads(1);
  const cv::Mat photo = Photo(static_cast<int>(state.range(0)));
  cv::Mat exg(photo.size(), CV_8UC1);
  // A plant mask: 2G − R − B above a fixed level.
  cv::Mat channels[3];
  cv::split(photo, channels);
  cv::Mat index;
  cv::addWeighted(channels[1], 2.0, channels[0], -1.0, 0.0, index, CV_16S);
  cv::subtract(index, channels[2], index, cv::noArray(), CV_16S);
  cv::compare(index, 20, exg, cv::CMP_GT);
  RowDetector detector{RowDetectorOptions{}};
  for (auto _ : state) {
    const RowDetection det = detector.Detect(exg);
    benchmark::DoNotOptimize(det.spacing_px);
  }
}
BENCHMARK(BM_RowDetectorOnMask)->Arg(320)->Arg(640)->Unit(benchmark::kMillisecond);

// The comb's inner loop (comb.h): one band's profile of N work columns, as
// the straight search's band-by-band comb sums it (thousands of times per
// photograph).
void BM_PhasorSum(benchmark::State& state) {
  std::vector<float> w(static_cast<size_t>(state.range(0)));
  for (size_t i = 0; i < w.size(); ++i) w[i] = static_cast<float>((i * 37) % 11) / 11.0F;
  double a0 = 0.1;
  for (auto _ : state) {
    const Phasor p = PhasorSum(std::span<const float>(w), a0, -0.21);
    benchmark::DoNotOptimize(p);
    a0 += 1e-9;
  }
}
BENCHMARK(BM_PhasorSum)->Arg(128)->Arg(384);

}  // namespace
}  // namespace plantscale::rows

BENCHMARK_MAIN();
