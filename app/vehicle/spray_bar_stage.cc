#include "app/vehicle/spray_bar_stage.h"


namespace plantscale::vehicle {

void SprayBarStage::Process(const VehicleFrame& frame, RunStatus& status, Publisher&) {
  bar_.Poll(frame.utime);
  if (command_closed_) bar_.Command(frame.utime, 0);
  for (std::string& line : bar_.HealthFaults()) status.faults.push_back(std::move(line));
  if (bar_.status().failsafe) status.failsafe = true;
}

}  // namespace plantscale::vehicle
