#include "evaluation/log_eval.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <plantscale_lcmtypes/plantscale_event_t.hpp>

#include "app/config/config_loader.h"
#include "app/telemetry_commands.h"
#include "telemetry/channels.h"
#include "telemetry/codec.h"
#include "telemetry/log.h"

namespace plantscale::app {
namespace {
namespace fs = std::filesystem;

fs::path Temp(const std::string& name) {
  return fs::temp_directory_path() /
         ("plantscale_logeval_" + std::to_string(::getpid()) + "_" + name);
}

sim::SimulatorOptions Field(uint64_t seed, double length_m) {
  sim::SimulatorOptions o = LoadSimulatorPreset("field", DefaultConfigDir());
  o.seed = seed;
  o.length_m = length_m;
  return o;
}

// Publishes a run over memq:// into a log, as `plantscale simulate --preset
// field --publish --fast --log` does.
fs::path PublishRun(const sim::SimulatorOptions& options, const std::string& name) {
  PublishArgs publish;
  publish.publish = true;
  publish.fast = true;
  publish.lcm_url = "memq://";
  publish.log = Temp(name).string();
  EXPECT_EQ(
      SimulateAndPublish(options, LoadProfiles("", "", "field", DefaultConfigDir()), publish,
                         SimRunConfigOf("field", DefaultConfigDir(), options)),
      0);
  return publish.log;
}

// The log's spraying scored from the log alone agrees with evaluate
// treatment driving the same preset and seed in process: the same chain and
// field, the shots rebuilt from the logged nozzle times. The whole 40 m of
// the preset (about 10 s to publish here, 220 crops): the vehicle's chain
// and evaluate treatment's differ in when odometry reaches the tracker, so a
// few plants' patches differ by 20-50 mm along; on 16-20 m (70-100 crops)
// that moves the RMS by up to 2 mm, on 40 m by at most 0.35 mm (seeds 1-5, 7).
TEST(EvaluateLog, AgreesWithEvaluateTreatmentOnTheSameSeed) {
  const sim::SimulatorOptions options = Field(1, 40.0);
  LogEvalOptions lo;
  lo.log = PublishRun(options, "run.lcmlog");
  const LogEvaluation log = EvaluateLog(lo);
  fs::remove(lo.log);
  EXPECT_EQ(log.run.preset, "field");
  EXPECT_EQ(log.run.seed, 1u);
  EXPECT_GT(log.messages.shots, 0);
  EXPECT_TRUE(log.problems.empty()) << log.problems.front();

  TreatmentEvalOptions to;
  to.sim = options;
  to.seeds = 1;
  to.profiles = LoadProfiles("", "", to.sim.preset, DefaultConfigDir());
  to.treatment = ProductTreatmentOptions(*to.profiles);
  const TreatmentEvaluation eval = EvaluateTreatment(to);
  ASSERT_GT(eval.ours.crop_hits, 100);
  ASSERT_GT(log.treatment.crop_hits, 100);
  EXPECT_NEAR(log.treatment.placement_rms_along_m, eval.ours.placement_rms_along_m, 0.0005);
  EXPECT_NEAR(log.treatment.placement_rms_across_m, eval.ours.placement_rms_across_m, 0.0005);
  EXPECT_NEAR(log.treatment.crop_hit_rate, eval.ours.crop_hit_rate, 0.02);
  EXPECT_EQ(log.treatment.crop_plants, eval.ours.crop_plants);  // the same scoring region
  EXPECT_EQ(log.treatment.weeds, eval.ours.weeds);
  EXPECT_NEAR(log.distance_m, eval.distance_m, 0.01);

  // Tracking: scored on the frames whose grid and truth the log kept.
  EXPECT_GT(log.tracking.frames, 600);
  EXPECT_GT(log.tracking.lateral_rmse_m, 0.0);
  EXPECT_LT(log.tracking.lateral_rmse_m, 0.01);
  EXPECT_EQ(log.tracking.init_trials, 1);
}

// A log that does not say which run it came from cannot be scored: the
// error names the log and the missing run_config event.
TEST(EvaluateLog, LogWithoutRunConfigIsRefusedNamingIt) {
  const fs::path with = PublishRun(Field(2, 3.0), "short.lcmlog");
  const fs::path without = Temp("no_run_config.lcmlog");
  {
    telemetry::LogReader in(with);
    telemetry::LogWriter out(without);
    int dropped = 0;
    while (const auto e = in.Next()) {
      if (e->channel == telemetry::channels::kEvents) {
        const auto m =
            telemetry::Decode<plantscale_event_t>(e->channel, e->data.data(), e->data.size());
        ASSERT_TRUE(m.has_value());
        if (m->kind == "run_config") {
          ++dropped;
          continue;
        }
      }
      out.Write(e->channel, e->data.data(), e->data.size(), e->utime);
    }
    ASSERT_EQ(dropped, 1);
  }
  LogEvalOptions lo;
  lo.log = with;
  EXPECT_NO_THROW(EvaluateLog(lo));
  lo.log = without;
  try {
    EvaluateLog(lo);
    ADD_FAILURE() << "a log without run_config was scored";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find(without.string()), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("run_config"), std::string::npos) << e.what();
  }
  fs::remove(with);
  fs::remove(without);
}

TEST(EvaluateLog, MissingLogIsALogErrorNamingIt) {
  LogEvalOptions lo;
  lo.log = Temp("absent.lcmlog");
  try {
    EvaluateLog(lo);
    ADD_FAILURE() << "an absent log was scored";
  } catch (const telemetry::LogError& e) {
    EXPECT_NE(std::string(e.what()).find("absent.lcmlog"), std::string::npos) << e.what();
  }
}

TEST(RunConfig, RoundTripsAndRebuildsTheSimulatorOptions) {
  sim::SimulatorOptions so = LoadSimulatorPreset("field", DefaultConfigDir());
  so.seed = 42;
  so.length_m = 12.5;
  so.render.kind = sim::ImageKind::kRgb;
  const SimRunConfig run = SimRunConfigOf("field", DefaultConfigDir(), so);
  const SimRunConfig back = ParseRunConfig(RunConfigJson(run), "test.lcmlog");
  EXPECT_EQ(back.preset, "field");
  EXPECT_EQ(back.seed, 42u);
  EXPECT_DOUBLE_EQ(back.length_m, 12.5);
  EXPECT_EQ(back.image, "rgb");
  EXPECT_EQ(back.config_dir, run.config_dir);
  const sim::SimulatorOptions rebuilt = SimulatorOptionsOf(back, back.config_dir);
  EXPECT_EQ(rebuilt.seed, 42u);
  EXPECT_DOUBLE_EQ(rebuilt.length_m, 12.5);
  EXPECT_EQ(rebuilt.render.kind, sim::ImageKind::kRgb);
  EXPECT_THROW(ParseRunConfig("{\"preset\": \"field\"}", "test.lcmlog"), ConfigError);
  EXPECT_THROW(ParseRunConfig("not json", "test.lcmlog"), ConfigError);
}

}  // namespace
}  // namespace plantscale::app
