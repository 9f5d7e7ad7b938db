// The contract of `plantscale run` with a calibration: a folder written by
// `simulate --out --every 1`, run with its frame times and measured wheel
// odometry from the truth CSVs and the preset's camera as calibration,
// publishes the grid track and the nozzle commands that `simulate --publish`
// publishes for the same preset, seed and length. Both commands run in
// process through the command line, each writing an LCM log over memq://.

#include <gtest/gtest.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <map>
#include <plantscale_lcmtypes/plantscale_grid_state_t.hpp>
#include <plantscale_lcmtypes/plantscale_health_t.hpp>
#include <plantscale_lcmtypes/plantscale_nozzles_t.hpp>
#include <string>
#include <vector>

#include "app/commands.h"
#include "app/config/config_loader.h"
#include "telemetry/channels.h"
#include "telemetry/codec.h"
#include "telemetry/log.h"

namespace plantscale::app {
namespace {
namespace fs = std::filesystem;
namespace ch = telemetry::channels;

int RunCommandLine(std::vector<std::string> args) {
  args.insert(args.begin(), "plantscale");
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  CLI::App cli;
  cli.require_subcommand(1);
  CommandLine commands(cli);
  cli.parse(static_cast<int>(argv.size()), argv.data());
  return commands.Run();
}

// What a log says about the grid and the bar; times from the first nozzle
// message (the first frame) on.
struct RunRecord {
  std::map<int, double> offset_m;         // PLANTSCALE_GRID by frame index
  std::map<int, int64_t> grid_utime;      // relative
  std::vector<int64_t> nozzles_utime;     // relative, one per PLANTSCALE_NOZZLES
  std::vector<std::vector<int8_t>> open;  // per message
  std::vector<plantscale_shot_t> shots;   // times relative
  std::vector<std::string> faults;        // every fault of every heartbeat
};

RunRecord ReadRun(const fs::path& log) {
  telemetry::LogReader reader(log);
  RunRecord r;
  int64_t epoch = -1;
  std::vector<plantscale_grid_state_t> grids;
  while (const auto e = reader.Next()) {
    if (e->channel == ch::kGrid) {
      const auto g =
          telemetry::Decode<plantscale_grid_state_t>(e->channel, e->data.data(), e->data.size());
      if (g) grids.push_back(*g);
    } else if (e->channel == ch::kNozzles) {
      const auto n =
          telemetry::Decode<plantscale_nozzles_t>(e->channel, e->data.data(), e->data.size());
      if (!n) continue;
      if (epoch < 0) epoch = n->utime;
      r.nozzles_utime.push_back(n->utime - epoch);
      r.open.push_back(n->open);
      for (plantscale_shot_t s : n->shots) {
        s.open_utime -= epoch;
        s.close_utime -= epoch;
        r.shots.push_back(s);
      }
    } else if (e->channel == ch::kHealth) {
      const auto h =
          telemetry::Decode<plantscale_health_t>(e->channel, e->data.data(), e->data.size());
      if (h) r.faults.insert(r.faults.end(), h->faults.begin(), h->faults.end());
    }
  }
  EXPECT_EQ(reader.error(), "") << log;
  for (const plantscale_grid_state_t& g : grids) {
    r.offset_m[g.frame_index] = g.state[0];
    r.grid_utime[g.frame_index] = g.utime - epoch;
  }
  return r;
}

class RunContract : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("plantscale_run_contract_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

TEST_F(RunContract, FolderWithTruthCsvsRunsAsSimulatePublish) {
  const std::string seed = "3", length = "9";
  const fs::path out = dir_ / "pass";
  ASSERT_EQ(RunCommandLine({"simulate", "--out", out.string(), "--preset", "field", "--seed", seed,
                            "--length-m", length, "--every", "1", "--quiet"}),
            0);
  // The field preset's camera (config/presets/field.yaml: camera: thesis).
  const fs::path calibration = DefaultConfigDir() / "cameras" / "thesis.yaml";
  const fs::path cam_log = dir_ / "cam.lcmlog", sim_log = dir_ / "sim.lcmlog";
  ASSERT_EQ(RunCommandLine({"run", "--camera", (out / "frames").string(), "--calibration",
                            calibration.string(), "--preset", "field", "--frame-times",
                            (out / "truth" / "frames.csv").string(), "--odometry",
                            (out / "truth" / "odometry.csv").string(), "--fast", "--log",
                            cam_log.string(), "--lcm-url", "memq://"}),
            0);
  ASSERT_EQ(
      RunCommandLine({"simulate", "--publish", "--preset", "field", "--seed", seed, "--length-m",
                      length, "--fast", "--log", sim_log.string(), "--lcm-url", "memq://"}),
      0);
  const RunRecord cam = ReadRun(cam_log), sim = ReadRun(sim_log);

  // The same frames, at the same times, placing the grid in the same place.
  ASSERT_GT(sim.offset_m.size(), 100u);
  ASSERT_EQ(cam.offset_m.size(), sim.offset_m.size());
  double sum2 = 0.0;
  for (const auto& [frame, offset] : sim.offset_m) {
    ASSERT_TRUE(cam.offset_m.count(frame)) << "frame " << frame << " missing from run's track";
    EXPECT_EQ(cam.grid_utime.at(frame), sim.grid_utime.at(frame)) << "frame " << frame;
    sum2 += std::pow(cam.offset_m.at(frame) - offset, 2);
  }
  const double rmse_m = std::sqrt(sum2 / static_cast<double>(sim.offset_m.size()));
  std::cout << std::scientific << std::setprecision(3) << "grid track: " << sim.offset_m.size()
            << " frames, lateral RMSE run vs simulate " << rmse_m << " m\n";
  EXPECT_LE(rmse_m, 1e-4);

  // The same nozzle commands: every message's open mask and every shot.
  EXPECT_EQ(cam.nozzles_utime, sim.nozzles_utime);
  EXPECT_EQ(cam.open, sim.open);
  ASSERT_GT(sim.shots.size(), 10u);
  ASSERT_EQ(cam.shots.size(), sim.shots.size());
  double worst_m = 0.0;
  for (size_t i = 0; i < sim.shots.size(); ++i) {
    const plantscale_shot_t &a = cam.shots[i], &b = sim.shots[i];
    EXPECT_EQ(a.nozzle, b.nozzle) << "shot " << i;
    EXPECT_EQ(a.open_utime, b.open_utime) << "shot " << i;
    EXPECT_EQ(a.close_utime, b.close_utime) << "shot " << i;
    EXPECT_EQ(a.plant_id, b.plant_id) << "shot " << i;
    worst_m = std::max({worst_m, std::abs(a.position_m[0] - b.position_m[0]),
                        std::abs(a.position_m[1] - b.position_m[1])});
  }
  std::cout << "nozzles: " << sim.nozzles_utime.size() << " messages, " << sim.shots.size()
            << " shots compared, largest position difference " << worst_m << " m\n";
  EXPECT_LE(worst_m, 1e-4);
}

// A calibration whose image size is not the frames': every frame is refused
// and said so in the heartbeat; the run ends normally.
TEST_F(RunContract, CalibrationOfAnotherImageSizeRefusesFramesAsFaults) {
  const fs::path out = dir_ / "pass";
  ASSERT_EQ(RunCommandLine({"simulate", "--out", out.string(), "--preset", "testbed", "--length-m",
                            "0.5", "--quiet"}),
            0);
  const fs::path log = dir_ / "cam.lcmlog";
  ASSERT_EQ(RunCommandLine({"run", "--camera", (out / "frames").string(), "--calibration",
                            "sanchiz_pla_66", "--preset", "testbed", "--frame-times",
                            (out / "truth" / "frames.csv").string(), "--odometry",
                            (out / "truth" / "odometry.csv").string(), "--fast", "--log",
                            log.string(), "--lcm-url", "memq://"}),
            0);
  const RunRecord run = ReadRun(log);
  EXPECT_TRUE(run.offset_m.empty());  // no frame accepted, no grid
  bool said = false;
  for (const std::string& f : run.faults) {
    said = said || f.find("is 640x480 px, the calibration is 768x576 px") != std::string::npos;
  }
  EXPECT_TRUE(said) << "no heartbeat fault names the image size";
  for (const std::vector<int8_t>& open : run.open) {
    for (int8_t o : open) EXPECT_EQ(o, 0);
  }
}

}  // namespace
}  // namespace plantscale::app
