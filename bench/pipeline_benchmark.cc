// Whole-frame speed of the vehicle pipeline (engine/pipeline): segmentation,
// tracking, classification, the treatment map and the scheduler's ticks of
// the frame's odometry, per frame in steady state, at 640×480 and 1280×960
// (the same view: focal length kept, pixels halved). Goals (issue): at most
// 2 ms per frame at 640×480 and 6 ms at 1280×960 on one core; heap
// allocations per frame measured and reported (goal: none).
// Run: build/bench/pipeline_benchmark --benchmark_repetitions=3
//
// Each resolution renders a 300-frame pass of the field preset once (not
// timed); a fresh pipeline is warmed on its first 60 frames (the tracker
// locks) and then timed one frame per iteration, each with the odometry
// samples that came with it (Pipeline::Step). When the pass ends the
// pipeline is rebuilt and warmed again outside the timing, so timestamps
// always increase and the grid never jumps. 480 iterations: each of the
// 240 timed frames twice, the same frames at both resolutions. treat:1 is
// the product; treat:0 (segmentation and tracking only) shows what the
// treatment chain adds.
//
// Counters, per timed frame:
//   frame_us            the frame's thread CPU time (the benchmark's Time is
//                       the same frames in real time)
//   threshold_us        one cv::threshold pass over the same image (a memory
//                       pass), timed between the frames, outside the timing
//   ratio_to_threshold  frame_us / threshold_us
//   allocs_per_frame    operator new / new[] calls (every variant) during Step
//   c_allocs_per_frame  malloc-family calls made directly (not through
//                       operator new): cv::Mat buffers (cv::fastMalloc), Eigen
//                       dynamic-size matrices, C code
//   alloc_kb_per_frame  bytes asked for by both, kB
//   tracking_fraction   timed frames on which the tracker was tracking
#include <benchmark/benchmark.h>
#include <malloc.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <ctime>
#include <memory>
#include <new>
#include <numbers>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "app/config/learned_model.h"
#include "engine/geometry/test_cameras.h"
#include "engine/motion/visual_odometry.h"
#include "engine/pipeline/pipeline.h"
#include "engine/sim/simulator.h"
#include "engine/treatment/treatment_system.h"

// ---------------------------------------------------------------------------
// Allocation counting. Counted only while g_counting is set (around the
// timed pipeline calls); the benchmark is single-threaded there.
namespace {

std::atomic<bool> g_counting{false};
std::atomic<int64_t> g_new_calls{0};
std::atomic<int64_t> g_c_calls{0};
std::atomic<int64_t> g_bytes{0};

inline void CountNew(std::size_t size) {
  if (g_counting.load(std::memory_order_relaxed)) {
    g_new_calls.fetch_add(1, std::memory_order_relaxed);
    g_bytes.fetch_add(static_cast<int64_t>(size), std::memory_order_relaxed);
  }
}
inline void CountC(std::size_t size) {
  if (g_counting.load(std::memory_order_relaxed)) {
    g_c_calls.fetch_add(1, std::memory_order_relaxed);
    g_bytes.fetch_add(static_cast<int64_t>(size), std::memory_order_relaxed);
  }
}

}  // namespace

// glibc's own entry points: the replacements below forward to them, so that
// operator new is not counted twice (once as new, once as malloc).
extern "C" {
void* __libc_malloc(std::size_t size);
void* __libc_calloc(std::size_t n, std::size_t size);
void* __libc_realloc(void* p, std::size_t size);
void* __libc_memalign(std::size_t alignment, std::size_t size);
void* __libc_valloc(std::size_t size);
void* __libc_pvalloc(std::size_t size);
void __libc_free(void* p);
}

namespace {

void* NewOrThrow(std::size_t size) {
  CountNew(size);
  if (size == 0) size = 1;
  for (;;) {
    if (void* p = __libc_malloc(size)) return p;
    std::new_handler handler = std::get_new_handler();
    if (handler == nullptr) throw std::bad_alloc();
    handler();
  }
}
void* AlignedNewOrThrow(std::size_t size, std::align_val_t align) {
  CountNew(size);
  if (size == 0) size = 1;
  for (;;) {
    if (void* p = __libc_memalign(static_cast<std::size_t>(align), size)) return p;
    std::new_handler handler = std::get_new_handler();
    if (handler == nullptr) throw std::bad_alloc();
    handler();
  }
}

}  // namespace

// Interposed C allocation (glibc allows the executable to replace these):
// OpenCV's cv::Mat buffers and Eigen's dynamic matrices go through them.
extern "C" {
void* malloc(std::size_t size) noexcept {
  CountC(size);
  return __libc_malloc(size);
}
void* calloc(std::size_t n, std::size_t size) noexcept {
  CountC(n * size);
  return __libc_calloc(n, size);
}
void* realloc(void* p, std::size_t size) noexcept {
  CountC(size);
  return __libc_realloc(p, size);
}
void free(void* p) noexcept { __libc_free(p); }
void* memalign(std::size_t alignment, std::size_t size) noexcept {
  CountC(size);
  return __libc_memalign(alignment, size);
}
void* aligned_alloc(std::size_t alignment, std::size_t size) noexcept {
  CountC(size);
  return __libc_memalign(alignment, size);
}
int posix_memalign(void** out, std::size_t alignment, std::size_t size) noexcept {
  if (alignment % sizeof(void*) != 0 || (alignment & (alignment - 1)) != 0 || alignment == 0) {
    return EINVAL;
  }
  CountC(size);
  void* p = __libc_memalign(alignment, size);
  if (p == nullptr) return ENOMEM;
  *out = p;
  return 0;
}
void* valloc(std::size_t size) noexcept {
  CountC(size);
  return __libc_valloc(size);
}
void* pvalloc(std::size_t size) noexcept {
  CountC(size);
  return __libc_pvalloc(size);
}
}

void* operator new(std::size_t size) { return NewOrThrow(size); }
void* operator new[](std::size_t size) { return NewOrThrow(size); }
void* operator new(std::size_t size, const std::nothrow_t&) noexcept {
  try {
    return NewOrThrow(size);
  } catch (...) {
    return nullptr;
  }
}
void* operator new[](std::size_t size, const std::nothrow_t&) noexcept {
  try {
    return NewOrThrow(size);
  } catch (...) {
    return nullptr;
  }
}
void* operator new(std::size_t size, std::align_val_t align) { return AlignedNewOrThrow(size, align); }
void* operator new[](std::size_t size, std::align_val_t align) {
  return AlignedNewOrThrow(size, align);
}
void* operator new(std::size_t size, std::align_val_t align, const std::nothrow_t&) noexcept {
  try {
    return AlignedNewOrThrow(size, align);
  } catch (...) {
    return nullptr;
  }
}
void* operator new[](std::size_t size, std::align_val_t align, const std::nothrow_t&) noexcept {
  try {
    return AlignedNewOrThrow(size, align);
  } catch (...) {
    return nullptr;
  }
}
void operator delete(void* p) noexcept { __libc_free(p); }
void operator delete[](void* p) noexcept { __libc_free(p); }
void operator delete(void* p, std::size_t) noexcept { __libc_free(p); }
void operator delete[](void* p, std::size_t) noexcept { __libc_free(p); }
void operator delete(void* p, const std::nothrow_t&) noexcept { __libc_free(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { __libc_free(p); }
void operator delete(void* p, std::align_val_t) noexcept { __libc_free(p); }
void operator delete[](void* p, std::align_val_t) noexcept { __libc_free(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { __libc_free(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { __libc_free(p); }
void operator delete(void* p, std::align_val_t, const std::nothrow_t&) noexcept { __libc_free(p); }
void operator delete[](void* p, std::align_val_t, const std::nothrow_t&) noexcept {
  __libc_free(p);
}

// ---------------------------------------------------------------------------
namespace plantscale::pipeline {
namespace {

constexpr int kFrames = 300;       // rendered per resolution
constexpr int kWarmFrames = 60;    // before timing, on a fresh pipeline
constexpr int kThresholds = 4;     // cv::threshold passes per frame, averaged

// The field preset (config/presets/field.yaml: 6-week cauliflower with
// weeds, slip, bumps, spacing drift, leaf and plant shadows) at `scale` ×
// the thesis camera's 640×480, the same view.
sim::SimulatorOptions FieldPass(int scale) {
  sim::SimulatorOptions o;
  o.preset = "bench-field";
  o.camera = geometry::testing::ThesisCamera();
  o.camera.virtual_plane_height_m = 0.1;
  o.camera.image_width_px *= scale;
  o.camera.image_height_px *= scale;
  o.camera.pixel_width_m /= scale;
  o.camera.pixel_height_m /= scale;
  o.field.plant_spacing_m = 0.467;
  o.field.nominal_plant_spacing_m = 0.45;
  o.field.crop_radius_m = 0.14;
  o.field.crop_height_ratio = 0.8;
  o.field.spacing_drift_fraction = 0.015;
  o.field.fractured_fraction = 0.1;
  o.field.weed_density_per_m2 = 6.0;
  o.vehicle.speed_m_s = 0.7;
  o.vehicle.zigzag_amplitude_m = 0.04;
  o.vehicle.odometry_scale_error = -0.035;
  o.vehicle.slip_bursts_per_100m = 4.0;
  o.vehicle.bump_pitch_sd_rad = 0.3 * std::numbers::pi / 180.0;
  o.vehicle.bump_roll_sd_rad = 0.2 * std::numbers::pi / 180.0;
  o.render.illumination_gradient = 0.15;
  o.render.plant_shadow_depth = 0.2;
  o.render.leaf_shadow_fraction = 0.2;
  o.render.leaf_shadow_depth = 0.5;
  o.length_m = 1.2 * kFrames * o.vehicle.speed_m_s / o.vehicle.frame_rate_hz;
  o.seed = 11;
  return o;
}

// The product's tracker options (app/config/profiles.cc ProductTrackerOptions:
// the nominal spacings, the crop and the vehicle's bounce as the grower
// knows them), mirrored here because app/ is not linked by benchmarks.
tracking::TrackerOptions ProductTracker(const sim::SimulatorOptions& s) {
  tracking::TrackerOptions o;
  o.rows_each_side = (s.field.rows - 1) / 2;
  o.row_spacing_m = s.field.NominalRowSpacing();
  o.plant_spacing_m = s.field.NominalPlantSpacing();
  o.track_width_m = s.vehicle.track_width_m;
  o.crop_radius_m = s.field.crop_radius_m;
  o.crop_height_m = s.field.crop_height_ratio * s.field.crop_radius_m;
  o.plant_height_sd_m = std::max(0.002, s.field.crop_radius_sd_fraction * o.crop_height_m);
  o.plant_offset_sd_m =
      std::max(0.002, std::hypot(s.field.planting_jitter_m, s.field.crop_lean_sd_m));
  const double wander = o.crop_height_m / tracking::TrackerOptions::kOffsetWalkCropHeightM;
  o.plant_offset_walk_across_sd_per_sqrt_m *= wander;
  o.plant_offset_walk_along_sd_per_sqrt_m *= wander;
  o.camera_pitch_sd_rad = std::max(1e-4, s.vehicle.bump_pitch_sd_rad);
  o.camera_roll_sd_rad = std::max(1e-4, s.vehicle.bump_roll_sd_rad);
  o.camera_height_sd_m = std::max(1e-4, s.vehicle.bump_height_sd_m);
  o.camera_bounce_correlation_s = s.vehicle.bump_correlation_s;
  return o;
}

// app/config/profiles.cc ProductPipelineOptions, likewise. Pixel-sized
// segmenter options (smoothing, notch closing, hull minimum area) are the
// product's as they are, not scaled with the resolution.
PipelineOptions ProductOptions(const sim::SimulatorOptions& s) {
  PipelineOptions o;
  o.treatment = treatment::TreatmentOptions{};
  o.segmenter = treatment::SegmenterOptionsFor(o.treatment.scheduler.mode);
  o.tracker = ProductTracker(s);
  return o;
}

struct Frame {
  int64_t utime = 0;
  int index = 0;
  cv::Mat image;
  std::vector<OdometrySample> odometry;  // since the previous frame
};

struct Pass {
  sim::SimulatorOptions options;
  std::unique_ptr<geometry::CameraModel> camera;
  std::vector<Frame> frames;
};

const Pass& PassAt(int scale) {
  static std::unique_ptr<Pass> passes[3];
  std::unique_ptr<Pass>& pass = passes[scale];
  if (pass) return *pass;
  pass = std::make_unique<Pass>();
  pass->options = FieldPass(scale);
  sim::Simulator simulator(pass->options);
  pass->camera = std::make_unique<geometry::CameraModel>(simulator.camera().options());
  sim::SimFrame f;
  while (static_cast<int>(pass->frames.size()) < kFrames && simulator.Next(f)) {
    Frame frame;
    frame.utime = f.truth.utime;
    frame.index = f.truth.index;
    frame.image = f.rendered.image.clone();
    for (const sim::OdometrySample& o : f.odometry) {
      frame.odometry.push_back({o.utime, o.left_m_s, o.right_m_s});
    }
    pass->frames.push_back(std::move(frame));
  }
  return *pass;
}

double ThreadCpuSeconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

// A fresh pipeline warmed on the pass's first frames.
// The shipped simulated-crop model (config/models/field-grey), read once.
LearnedOptions FieldGreyModel() {
  static const LearnedOptions learned = [] {
    const app::LearnedModel m =
        app::ReadLearnedModel(PLANTSCALE_SOURCE_DIR "/config/models/field-grey.onnx");
    LearnedOptions l;
    l.spec = m.spec;
    l.onnx = std::make_shared<const std::vector<uint8_t>>(m.onnx);
    l.source = m.onnx_path.string();
    return l;
  }();
  return learned;
}

std::unique_ptr<Pipeline> Warmed(const Pass& pass, bool treat, int camera, int64_t* opened,
                                 bool learned = false) {
  PipelineOptions options = ProductOptions(pass.options);
  options.treat = treat;
  if (learned) options.learned = FieldGreyModel();
  if (camera != 0) {  // the camera's motion as the second source, as `--visual-motion`
    const sim::FieldOptions& f = pass.options.field;
    options.motion.enabled = true;
    options.motion.camera_pitch = camera == 1;
    options.motion.visual = motion::VisualOdometryFor(f.crop_radius_m, f.crop_radius_m * f.crop_height_ratio);
  }
  auto p = std::make_unique<Pipeline>(*pass.camera, options,
                                      [opened](int64_t, uint64_t mask) { *opened += mask != 0; });
  for (int i = 0; i < kWarmFrames; ++i) {
    const Frame& f = pass.frames[static_cast<size_t>(i)];
    p->Step(f.utime, f.index, f.image, f.odometry);
  }
  return p;
}

void BM_PipelineFrame(benchmark::State& state) {
  cv::setNumThreads(1);
  const int scale = static_cast<int>(state.range(0));
  const bool treat = state.range(1) != 0;
  const int camera = static_cast<int>(state.range(2));
  const bool learned = state.range(3) != 0;
  const Pass& pass = PassAt(scale);
  if (static_cast<int>(pass.frames.size()) < kFrames) {
    state.SkipWithError("the pass ended before its frames were rendered");
    return;
  }
  int64_t opened = 0;
  std::unique_ptr<Pipeline> p = Warmed(pass, treat, camera, &opened, learned);
  if (learned && !p->learned()) {
    state.SkipWithError(p->learned_fault().c_str());
    return;
  }
  if (p->tracker().mode() != tracking::TrackerMode::kTracking) {
    state.SkipWithError("the tracker did not lock in the warm-up frames");
    return;
  }
  size_t next = kWarmFrames;
  cv::Mat mask;
  double frame_s = 0.0, threshold_s = 0.0;
  int64_t tracked = 0, restarts = 0;
  g_new_calls = 0, g_c_calls = 0, g_bytes = 0;
  for (auto _ : state) {
    if (next == pass.frames.size()) {
      state.PauseTiming();
      p.reset();
      p = Warmed(pass, treat, camera, &opened, learned);
      next = kWarmFrames;
      ++restarts;
      state.ResumeTiming();
    }
    const Frame& f = pass.frames[next++];
    g_counting.store(true, std::memory_order_relaxed);
    const double t0 = ThreadCpuSeconds();
    const FrameResult& r = p->Step(f.utime, f.index, f.image, f.odometry);
    const double t1 = ThreadCpuSeconds();
    g_counting.store(false, std::memory_order_relaxed);
    tracked += r.mode == tracking::TrackerMode::kTracking;
    frame_s += t1 - t0;
    // One memory pass over the same image, on the same machine load.
    state.PauseTiming();
    const double t2 = ThreadCpuSeconds();
    for (int k = 0; k < kThresholds; ++k) {
      cv::threshold(f.image, mask, 127, 255, cv::THRESH_BINARY);
      benchmark::DoNotOptimize(mask.data);
    }
    threshold_s += (ThreadCpuSeconds() - t2) / kThresholds;
    state.ResumeTiming();
  }
  const auto n = static_cast<double>(state.iterations());
  state.counters["frame_us"] = 1e6 * frame_s / n;
  state.counters["threshold_us"] = 1e6 * threshold_s / n;
  state.counters["ratio_to_threshold"] = frame_s / threshold_s;
  state.counters["allocs_per_frame"] = static_cast<double>(g_new_calls.load()) / n;
  state.counters["c_allocs_per_frame"] = static_cast<double>(g_c_calls.load()) / n;
  state.counters["alloc_kb_per_frame"] = static_cast<double>(g_bytes.load()) / 1024.0 / n;
  state.counters["tracking_fraction"] = static_cast<double>(tracked) / n;
  state.counters["restarts"] = static_cast<double>(restarts);
  state.SetLabel(std::to_string(pass.camera->width()) + "x" + std::to_string(pass.camera->height()));
}
// treat:1 is the product (the figures of the issue); treat:0 is segmentation
// and tracking only, so that the treatment chain's share shows in one run.
// camera:1 adds the camera's own motion (features, correspondence and the
// soil's pitch: MotionFusionOptions), camera:2 the same without the pitch.
// learned:1 runs the grower's learned model (config/models/field-grey, 320×240
// input) on every frame (issue 57: ≤ 20 ms for the whole frame).
BENCHMARK(BM_PipelineFrame)
    ->ArgNames({"scale", "treat", "camera", "learned"})
    ->Args({1, 1, 0, 0})
    ->Args({2, 1, 0, 0})
    ->Args({1, 0, 0, 0})
    ->Args({2, 0, 0, 0})
    ->Args({1, 1, 1, 0})
    ->Args({1, 1, 2, 0})
    ->Args({1, 1, 0, 1})
    ->Unit(benchmark::kMillisecond)
    ->Iterations(2 * (kFrames - kWarmFrames));  // each timed frame of the pass twice

}  // namespace
}  // namespace plantscale::pipeline

BENCHMARK_MAIN();
