// A day's run in bounded memory (issue 35): the vehicle of `simulate
// --publish --fast --log` (the product's runner, pipeline, publisher, LCM
// over memq:// and the log writer) drives 5 km of the field preset's bed.
// Its peak resident set (VmHWM) after 5 km is within 10 % of the peak after
// 1 km, and every crop of the last 100 m the bar passed is sprayed. Label
// `soak` (ctest -L soak); about 20 CPU minutes (`./plantscale.sh soak`). PLANTSCALE_SOAK_SEED and
// PLANTSCALE_SOAK_LENGTH_M change the run (docs/results/2026-11-27-soak.md).
#include <gtest/gtest.h>

#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "app/config/config_loader.h"
#include "app/config/profiles.h"
#include "app/config/run_config.h"
#include "app/telemetry_commands.h"
#include "engine/treatment/simulated_bar.h"
#include "evaluation/treatment_eval.h"
#include "evaluation/treatment_score.h"

namespace plantscale::app {
namespace {

// A field of /proc/self/status in kB ("VmHWM", "VmRSS"); −1 when missing.
long StatusKb(const std::string& key) {
  std::ifstream in("/proc/self/status");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind(key + ":", 0) == 0) return std::stol(line.substr(key.size() + 1));
  }
  return -1;
}

struct Memory {
  double distance_m = 0.0;
  long peak_kb = -1;      // VmHWM
  long resident_kb = -1;  // VmRSS
};

Memory Sample(double distance_m) { return {distance_m, StatusKb("VmHWM"), StatusKb("VmRSS")}; }

// What the test watches of the run: memory at the marks (and at the end),
// and the true track of the vehicle over the stretch it scores.
struct Watch {
  std::vector<double> marks_m;
  std::vector<Memory> samples;
  double score_from_m = 0.0;  // truth distance from which the bar is scored
  bool scoring = false;
  std::vector<treatment::FieldPose> track;
  std::optional<treatment::SimulatedBar> bar;
};

class WatchStage : public vehicle::Stage {
 public:
  explicit WatchStage(Watch& w) : w_(w) {}
  std::string name() const override { return "soak_watch"; }
  void Process(const vehicle::VehicleFrame& frame, vehicle::RunStatus&,
               vehicle::Publisher&) override {
    if (frame.truth == nullptr) return;
    const double d = frame.truth->distance_m;
    while (next_ < w_.marks_m.size() && d >= w_.marks_m[next_]) {
      w_.samples.push_back(Sample(d));
      std::cout << "soak: " << d << " m, VmHWM " << w_.samples.back().peak_kb << " kB, VmRSS "
                << w_.samples.back().resident_kb << " kB" << std::endl;
      ++next_;
    }
    w_.scoring = d >= w_.score_from_m;
    if (w_.scoring) {
      const sim::Pose2& p = frame.truth->pose;
      w_.track.push_back({frame.utime, p.x_m, p.y_m, p.heading_rad});
    }
  }
  void Finish(int64_t, vehicle::Publisher&) override {
    w_.samples.push_back(Sample(w_.track.empty() ? 0.0 : -1.0));
  }

 private:
  Watch& w_;
  size_t next_ = 0;
};

double EnvOr(const char* name, double fallback) {
  const char* v = std::getenv(name);
  return v != nullptr && *v != '\0' ? std::stod(v) : fallback;
}

TEST(Soak, FiveKilometresInFlatMemorySprayingToTheEnd) {
  const double length_m = EnvOr("PLANTSCALE_SOAK_LENGTH_M", 5000.0);
  const auto seed = static_cast<uint64_t>(EnvOr("PLANTSCALE_SOAK_SEED", 7));
  const std::filesystem::path dir = DefaultConfigDir();
  sim::SimulatorOptions so = LoadSimulatorPreset("field", dir);
  so.length_m = length_m;
  so.seed = seed;
  const std::filesystem::path log =
      std::filesystem::temp_directory_path() / ("plantscale_soak_" + std::to_string(::getpid()) + ".lcmlog");
  PublishArgs args;
  args.publish = true;
  args.fast = true;
  args.lcm_url = "memq://";
  args.log = log.string();
  args.command_key.accept_unsigned = true;

  Watch w;
  w.marks_m = {1000.0, length_m};
  // The bar is scored over the last 100 m it passed (and a little before,
  // so that the shots over the first of those crops are whole).
  const Profiles profiles = LoadProfiles("", "", "field", dir);  // the preset's crop and vehicle
  const pipeline::PipelineOptions engine = ProductPipelineOptions(profiles);
  const treatment::SprayBarOptions bar = engine.treatment.scheduler.bar;
  w.score_from_m = length_m - 100.0 - 5.0;
  w.bar.emplace(bar, bar.valve_latency_s, engine.treatment.scheduler.tick_s);
  VehicleHooks hooks;
  hooks.stages.push_back(std::make_unique<WatchStage>(w));
  hooks.nozzle_sink = [&w](int64_t utime, uint64_t mask) {
    if (w.scoring) w.bar->Command(utime, mask);
  };
  ASSERT_EQ(SimulateAndPublish(so, profiles, args, SimRunConfigOf("field", dir, so), std::move(hooks)), 0);
  std::filesystem::remove(log);

  ASSERT_GE(w.samples.size(), 2u);
  const Memory& at_1km = w.samples[0];
  const Memory& at_end = w.samples[1];
  ASSERT_GT(at_1km.peak_kb, 0);
  std::cout << "soak: peak resident set " << at_1km.peak_kb / 1024.0 << " MB after 1 km, "
            << at_end.peak_kb / 1024.0 << " MB after " << length_m / 1000.0 << " km" << std::endl;
  // Flat: the peak after 5 km within 10 % of the peak after 1 km.
  EXPECT_LE(static_cast<double>(at_end.peak_kb), 1.10 * static_cast<double>(at_1km.peak_kb));

  // Every crop of the last 100 m the bar passed is sprayed.
  ASSERT_FALSE(w.track.empty());
  SprayScoreRegion region;
  region.y_end_m = w.track.back().y_m - bar.bar_offset_m - 0.3;
  region.y_begin_m = region.y_end_m - 100.0;
  region.bed_half_width_m = 0.5 * so.field.rows * so.field.row_spacing_m;
  region.patch_half_size_m = 0.45 * std::min(so.field.row_spacing_m, so.field.plant_spacing_m);
  sim::Simulator field_only(so);  // the same field, plant for plant
  const SprayScore score = ScoreSpray(field_only.field(), w.bar->Shots(w.track), region);
  std::cout << "soak: last 100 m: " << score.crop_hits << " of " << score.crop_plants
            << " crops sprayed" << std::endl;
  for (const MissedCrop& m : score.missed) {
    std::cout << "soak: missed crop " << m.plant_id << " at (" << m.root_m.x() << ", " << m.root_m.y()
              << ") m, spray " << 1000.0 * m.nearest_spray_m << " mm from its root" << std::endl;
  }
  EXPECT_GT(score.crop_plants, 500);  // 3 rows × 100 m / 0.467 m
  EXPECT_EQ(score.crop_hits, score.crop_plants);
}

}  // namespace
}  // namespace plantscale::app
