#pragma once
// The spray bar in the vehicle runner: a Stage that keeps the bar's
// watchdog running every frame and reports its state in the heartbeat
// (PLANTSCALE_HEALTH: fail-safe flag and one fault line per reason or
// faulty nozzle); the bar's state as telemetry is telemetry/can/nozzle_bar.h.
//
// The treatment scheduler drives the nozzles through SprayBar::Sink(); until
// one does, the stage commands all nozzles closed every frame
// (`command_closed` true) so the bar stays supervised and its hold is fed.

#include "telemetry/can/simulated_bar.h"
#include "telemetry/can/spray_bar.h"
#include "app/vehicle/runner.h"

namespace plantscale::vehicle {

using telemetry::can::SimulatedBar;
using telemetry::can::SprayBar;

class SprayBarStage : public Stage {
 public:
  SprayBarStage(SprayBar& bar, bool command_closed) : bar_(bar), command_closed_(command_closed) {}
  std::string name() const override { return "spray_bar"; }
  // Polls the bar (and commands closed when asked), appends
  // bar.HealthFaults() to status.faults and forces status.failsafe while the
  // bar is fail-safe. Add it before HealthStage and after the treatment stage.
  void Process(const VehicleFrame& frame, RunStatus& status, Publisher& publisher) override;

 private:
  SprayBar& bar_;
  bool command_closed_;
};

// Plays the bar's end in a simulated run: steps `bar` on the frame's
// message time (reads and acknowledges commands, sends heartbeats and faults).
class SimulatedBarStage : public Stage {
 public:
  explicit SimulatedBarStage(SimulatedBar& bar) : bar_(bar) {}
  std::string name() const override { return "simulated_bar"; }
  void Process(const VehicleFrame& frame, RunStatus&, Publisher&) override {
    bar_.Step(frame.utime);
  }

 private:
  SimulatedBar& bar_;
};

}  // namespace plantscale::vehicle
