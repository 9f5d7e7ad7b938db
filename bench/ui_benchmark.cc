// ui benchmarks (issue 9 figures), run under Xvfb: `xvfb-run -a build/bench/ui_benchmark`.
//  - BM_StationFrame: one station frame (update the scene from the run model,
//    render the 1280×720 window) with a 100 m bed map loaded (the vehicle has
//    driven 100 m; counter map_length_m) while the log plays on at 60 frames
//    per log second; target ≥ 60 fps, i.e. ≤ 16.7 ms per frame.
//  - BM_Report/40, /1000, /5000: `plantscale report` of a 40 m, 1 km and 5 km
//    run; targets ≤ 10 s and ≤ 60 s, linear in distance (ratio_5km_1km ≈ 5).
//  - BM_ReviewFrame/5000: `station --review` of a 5 km run: one frame of
//    the tour (StationController::TourStep: 6 m, 40 m, 300 m and whole-bed
//    views, panning); target ≥ 30 fps. Counter peak_rss_mb.
// All use the synthetic run (ui/synthetic_run.h) until the tracker and the
// treatment map publish for real.

#include <benchmark/benchmark.h>

#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <map>

#include "review/log_timeline.h"
#include "review/synthetic_run.h"
#include "ui/canvas.h"
#include "ui/report.h"
#include "ui/station.h"
#include "ui/station_controller.h"
#include "ui/station_sources.h"

namespace plantscale::ui {
namespace {

// User + system CPU of the whole process (llvmpipe renders on its own threads).
double ProcessCpuSeconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_utime.tv_sec + u.ru_stime.tv_sec) +
         1e-6 * static_cast<double>(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

// The map covers `bed_m` of bed (the vehicle is 1 m past it: tiles are sent
// once the camera footprint has passed them) and `play_s` of the run is
// still to play.
review::LogTimeline BedLoaded(double bed_m, double play_s) {
  review::SyntheticRunOptions run;
  run.length_m = bed_m + 1.0 + play_s * run.speed_m_s;
  review::LogTimeline timeline(review::SyntheticRun(run), "");
  timeline.Seek((bed_m + 1.0) / run.speed_m_s);
  return timeline;
}

// Along-bed length the map tiles cover (m).
double MapLength(const review::RunModel& model) {
  double lo = 1e300, hi = -1e300;
  for (const auto& [key, t] : model.tiles()) {
    lo = std::min(lo, t.origin_m.y()), hi = std::max(hi, t.origin_m.y() + t.height * t.resolution_m);
  }
  return hi > lo ? hi - lo : 0.0;
}

void StationFrames(benchmark::State& state, bool partial_redraw) {
  if (!DisplayAvailable()) return state.SkipWithError("no DISPLAY: run under xvfb-run -a");
  review::LogTimeline timeline = BedLoaded(100.0, 30.0);
  StationOptions options;
  options.width_px = static_cast<int>(state.range(0));
  options.height_px = options.width_px * 9 / 16;
  Canvas canvas(options.width_px, options.height_px, /*offscreen=*/false);
  canvas.SetPartialRedraw(partial_redraw);
  StationScene scene(canvas, options);
  state.counters["map_length_m"] = MapLength(timeline.model());
  int64_t frames = 0;
  const double cpu0 = ProcessCpuSeconds();
  for (auto _ : state) {
    timeline.Advance(1.0 / 60.0);
    scene.Update(timeline.model(), timeline.now_utime(), timeline.position_s() / timeline.duration_s());
    canvas.window()->Render();
    ++frames;
  }
  state.counters["fps"] = benchmark::Counter(static_cast<double>(frames), benchmark::Counter::kIsRate);
  state.counters["process_cpu_ms_per_frame"] = 1e3 * (ProcessCpuSeconds() - cpu0) / static_cast<double>(frames);
  state.counters["tiles"] = static_cast<double>(timeline.model().tiles().size());
  state.counters["plants"] = static_cast<double>(timeline.model().plants().size());
}

void BM_StationFrame(benchmark::State& state) { StationFrames(state, true); }
BENCHMARK(BM_StationFrame)->Arg(1280)->Arg(960)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(3.0);

// Every viewport redrawn every frame: what a frame costs when everything
// changes at once (the window otherwise redraws only the viewports that did).
void BM_StationFrameFullRedraw(benchmark::State& state) { StationFrames(state, false); }
BENCHMARK(BM_StationFrameFullRedraw)->Arg(1280)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(3.0);

// The render alone, every viewport redrawn (nothing changes): what the GL side costs.
void BM_StationRenderOnly(benchmark::State& state) {
  if (!DisplayAvailable()) return state.SkipWithError("no DISPLAY: run under xvfb-run -a");
  review::LogTimeline timeline = BedLoaded(100.0, 0.0);
  StationOptions options;
  Canvas canvas(options.width_px, options.height_px, /*offscreen=*/false);
  canvas.SetPartialRedraw(false);
  StationScene scene(canvas, options);
  scene.Update(timeline.model(), timeline.now_utime(), 0.8);
  for (auto _ : state) canvas.window()->Render();
  state.counters["fps"] = benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_StationRenderOnly)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(2.0);

// The synthetic log of `length` metres, written once (outside the timing).
std::filesystem::path BenchLog(int64_t length) {
  const auto dir = std::filesystem::temp_directory_path() / "plantscale_ui_bench";
  std::filesystem::create_directories(dir);
  const auto log = dir / ("run" + std::to_string(length) + "m.lcmlog");
  if (!std::filesystem::exists(log)) {
    review::SyntheticRunOptions run;
    run.length_m = static_cast<double>(length);
    review::WriteSyntheticLog(log, run);
  }
  return log;
}

void BM_ReviewFrame(benchmark::State& state) {
  if (!DisplayAvailable()) return state.SkipWithError("no DISPLAY: run under xvfb-run -a");
  const review::ReviewRun run = review::LoadReviewRun(BenchLog(state.range(0)));
  StationOptions options;
  Canvas canvas(options.width_px, options.height_px, /*offscreen=*/false);
  StationScene scene(canvas, options);
  ReviewSource source(run.model, "bench");
  StationController controller(canvas, scene, source, options);
  controller.Frame(0.0);
  int i = 0;
  for (auto _ : state) {
    controller.TourStep(i++);
    controller.Frame(0.0);
  }
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  state.counters["fps"] = benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
  state.counters["peak_rss_mb"] = static_cast<double>(u.ru_maxrss) / 1024.0;
  state.counters["tiles"] = static_cast<double>(run.model->tiles().size());
  state.counters["plants"] = static_cast<double>(run.model->plants().size());
}
BENCHMARK(BM_ReviewFrame)->Arg(5000)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(400);

// `plantscale report` of a synthetic run of state.range(0) metres (40 m,
// 1 km, 5 km; the log is written once per length, outside the timing).
// Counters: ms_per_m, and at 5 km ratio_5km_1km, the time of 5 km over that
// of 1 km (5.0 when the cost is linear in distance). Targets: ≤ 10 s at
// 40 m, ≤ 60 s at 5 km.
std::map<int64_t, double>& ReportSeconds() {
  static std::map<int64_t, double> seconds;
  return seconds;
}

void BM_Report(benchmark::State& state) {
  const int64_t length = state.range(0);
  const auto log = BenchLog(length);
  const auto dir = log.parent_path();
  double seconds = 0.0;
  for (auto _ : state) {
    const auto start = std::chrono::steady_clock::now();
    const ReportResult r = WriteReport(log, dir / ("report" + std::to_string(length)));
    seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    benchmark::DoNotOptimize(r.summary.distance_m);
    state.counters["pictures"] = static_cast<double>(r.pictures.size());
  }
  ReportSeconds()[length] = seconds;
  state.counters["ms_per_m"] = 1e3 * seconds / static_cast<double>(length);
  state.counters["log_mb"] = static_cast<double>(std::filesystem::file_size(log)) / 1e6;
  if (length == 5000 && ReportSeconds().count(1000)) {
    state.counters["ratio_5km_1km"] = seconds / ReportSeconds()[1000];
  }
}
BENCHMARK(BM_Report)->Arg(40)->Arg(1000)->Arg(5000)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);

}  // namespace
}  // namespace plantscale::ui

BENCHMARK_MAIN();
