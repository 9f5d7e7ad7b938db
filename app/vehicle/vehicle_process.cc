#include "app/vehicle/vehicle_process.h"

#include <utility>

#include "app/vehicle/spray_bar_stage.h"
#include "telemetry/publisher.h"

namespace plantscale::vehicle {

namespace tm = plantscale::telemetry;

VehicleProcess::VehicleProcess(tm::Transport& lcm, const VehicleProcessOptions& options,
                               int64_t boot_utime)
    : transport_(&lcm) {
  if (!options.log.empty()) {
    log_ = std::make_unique<tm::LogWriter>(options.log);
    // The log takes the runner's message clock: a --fast simulated run logs
    // simulated time and replays at the real pace.
    logged_ = std::make_unique<tm::LoggingTransport>(
        lcm, *log_, [this] { return runner_ ? runner_->now_utime() : tm::WallUtime(); });
    transport_ = logged_.get();
  }
  publisher_ = std::make_unique<tm::Publisher>(*transport_, tm::PublisherOptions{});
  runner_ = std::make_unique<VehicleRunner>(
      *publisher_, RunnerOptions{options.real_time, options.run_config}, boot_utime);
  sim_truth_ = options.sim_truth;
}

void VehicleProcess::ListenForCommands(CommandAuthOptions auth) {
  runner_->ListenForCommands(*transport_, std::move(auth));
}

// With the treatment stage (a calibrated camera) its scheduler drives the
// bar through the bar's sink every tick; without one the bar stage commands
// every nozzle closed each frame so the bar stays supervised. The bar stage
// goes before HealthStage, which reports its fail-safe state and faults;
// the simulated bar steps after the treatment stage has commanded it.
void VehicleProcess::AddStages(const SprayBarEndpoint& endpoint,
                               const std::optional<PipelineSetup>& pipeline, VehicleHooks hooks) {
  tm::can::SprayBar* bar = endpoint.bar.get();
  treatment::NozzleSink nozzle_sink = pipeline ? pipeline->nozzle_sink : treatment::NozzleSink{};
  if (hooks.nozzle_sink) {
    nozzle_sink = [hook = hooks.nozzle_sink, other = nozzle_sink](int64_t utime, uint64_t mask) {
      if (other) other(utime, mask);
      hook(utime, mask);
    };
  }
  if (bar != nullptr) {
    const bool scheduler_drives_bar = pipeline.has_value();
    if (scheduler_drives_bar) {
      const treatment::NozzleSink to_bar = bar->Sink();
      const treatment::NozzleSink other = nozzle_sink;
      nozzle_sink = [to_bar, other](int64_t utime, uint64_t mask) {
        if (other) other(utime, mask);
        to_bar(utime, mask);
      };
    }
    runner_->AddStage(std::make_unique<SprayBarStage>(*bar, !scheduler_drives_bar));
  }
  runner_->AddStage(std::make_unique<OdometryStage>());
  const BlobView* blobs = nullptr;
  if (pipeline) {
    auto stage = std::make_unique<PipelineStage>(pipeline->camera, pipeline->options, nozzle_sink);
    blobs = stage.get();
    pipeline_stage_ = stage.get();
    runner_->AddStage(std::move(stage));
  } else {
    auto stage = std::make_unique<SegmentationStage>(
        treatment::SegmenterOptionsFor(treatment::TreatmentOptions{}.scheduler.mode));
    blobs = stage.get();
    runner_->AddStage(std::move(stage));
  }
  // After every stage that reports faults or the fail-safe state this frame
  // (the runner starts each frame's fault list afresh from the source).
  runner_->AddStage(std::make_unique<RecordsStage>(logged_.get()));
  runner_->AddStage(std::make_unique<HealthStage>());
  runner_->AddStage(std::make_unique<ThumbnailStage>(ThumbnailOptions{}, blobs));
  if (endpoint.simulated) {
    runner_->AddStage(std::make_unique<SimulatedBarStage>(*endpoint.simulated));
  }
  if (sim_truth_) runner_->AddStage(std::make_unique<SimTruthStage>());
  for (std::unique_ptr<Stage>& stage : hooks.stages) runner_->AddStage(std::move(stage));
}

RunSummary VehicleProcess::Run(FrameSource& source, const std::atomic<bool>* stop) {
  return runner_->Run(source, stop);
}

}  // namespace plantscale::vehicle
