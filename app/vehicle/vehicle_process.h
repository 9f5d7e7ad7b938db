#pragma once
// The vehicle process's wiring, one for `plantscale run`, `plantscale
// simulate --publish` and the fault-injection tests (evaluation/fault_injection*):
// the LCM transport (memq:// in tests) with the log written beside it, the
// publisher, the runner, and its stages in the product's order (spray bar,
// odometry, pipeline or segmentation alone, records, heartbeat, thumbnails,
// the simulated bar, the simulator's truth). What the process does when a
// part fails is docs/faults.md.

#include <atomic>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "app/vehicle/runner.h"
#include "app/vehicle/stages.h"
#include "engine/geometry/camera_model.h"
#include "engine/pipeline/pipeline.h"
#include "telemetry/can/simulated_bar.h"
#include "telemetry/can/spray_bar.h"
#include "telemetry/log.h"

namespace plantscale::vehicle {

// The spray bar of --can: a SocketCAN interface, or a SimulatedBar in
// process over a socketpair (simulate only); both null: no bar.
struct SprayBarEndpoint {
  std::unique_ptr<telemetry::can::SprayBar> bar;
  std::unique_ptr<telemetry::can::SimulatedBar> simulated;
};

// The vehicle pipeline (a calibrated camera); without one, segmentation
// alone for the thumbnails.
struct PipelineSetup {
  const geometry::CameraModel& camera;
  pipeline::PipelineOptions options;
  treatment::NozzleSink nozzle_sink = {};  // besides the spray bar: every tick's open mask
};

// What a whole-system test adds to the vehicle (tests/soak_system_test.cc):
// stages run after the product's, and a sink that sees every tick's open
// mask as the spray bar does.
struct VehicleHooks {
  std::vector<std::unique_ptr<Stage>> stages;
  treatment::NozzleSink nozzle_sink;
};

struct VehicleProcessOptions {
  bool real_time = true;   // false: --fast
  std::string log;         // LCM log file; empty: none
  std::string run_config;  // RunnerOptions::run_config
  bool sim_truth = false;  // the simulator's truth on its channels
};

class VehicleProcess {
 public:
  // Throws LogError when the log cannot be created. `lcm` must outlive it.
  VehicleProcess(telemetry::Transport& lcm, const VehicleProcessOptions& options,
                 int64_t boot_utime);
  // What the process publishes and subscribes through (the logging one when
  // there is a log): frame sources take odometry from it.
  telemetry::Transport& transport() { return *transport_; }
  // Station commands on transport(), authenticated by `auth`.
  void ListenForCommands(CommandAuthOptions auth);
  // Adds every stage (once). `bar` must outlive the process.
  void AddStages(const SprayBarEndpoint& bar, const std::optional<PipelineSetup>& pipeline,
                 VehicleHooks hooks = {});
  RunSummary Run(FrameSource& source, const std::atomic<bool>* stop = nullptr);

  VehicleRunner& runner() { return *runner_; }
  const telemetry::Publisher& publisher() const { return *publisher_; }
  const telemetry::LogWriter* log() const { return log_.get(); }
  const telemetry::LoggingTransport* logging() const { return logged_.get(); }
  const PipelineStage* pipeline_stage() const { return pipeline_stage_; }

 private:
  std::unique_ptr<telemetry::LogWriter> log_;
  std::unique_ptr<telemetry::LoggingTransport> logged_;
  telemetry::Transport* transport_;
  std::unique_ptr<telemetry::Publisher> publisher_;
  std::unique_ptr<VehicleRunner> runner_;
  const PipelineStage* pipeline_stage_ = nullptr;
  bool sim_truth_ = false;
};

}  // namespace plantscale::vehicle
