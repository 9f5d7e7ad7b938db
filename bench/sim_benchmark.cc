// Simulator speed (issue: at least 200 frames/s at 640×480 for the
// simulator alone). Run: build/bench/sim_benchmark
#include <benchmark/benchmark.h>

#include <numbers>

#include "engine/geometry/test_cameras.h"
#include "engine/sim/simulator.h"

namespace plantscale::sim {
namespace {

// The field preset's settings (config/presets/field.yaml) at 640×480.
SimulatorOptions FieldLike(ImageKind kind) {
  SimulatorOptions o;
  o.preset = "bench-field";
  o.camera = geometry::testing::ThesisCamera();
  o.camera.virtual_plane_height_m = 0.1;
  o.field.crop_radius_m = 0.14;
  o.field.fractured_fraction = 0.1;
  o.field.weed_density_per_m2 = 6.0;
  o.vehicle.slip_bursts_per_100m = 4.0;
  o.render.kind = kind;
  o.render.plant_shadow_depth = 0.2;
  o.length_m = 1000.0;
  o.seed = 7;
  return o;
}

void RunFrames(benchmark::State& state, ImageKind kind) {
  Simulator simulator(FieldLike(kind));
  SimFrame frame;
  for (auto _ : state) {
    if (!simulator.Next(frame)) state.SkipWithError("pass ended");
    benchmark::DoNotOptimize(frame.rendered.image.data);
  }
  state.counters["frames_per_s"] =
      benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}

void BM_SimulatorNirFrame640x480(benchmark::State& state) { RunFrames(state, ImageKind::kNir); }
void BM_SimulatorRgbFrame640x480(benchmark::State& state) { RunFrames(state, ImageKind::kRgb); }
BENCHMARK(BM_SimulatorNirFrame640x480)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_SimulatorRgbFrame640x480)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace plantscale::sim

BENCHMARK_MAIN();
