#pragma once
// The spray bar's state (SprayBarStatus) as the telemetry's NozzleBar, for
// PLANTSCALE_NOZZLES.

#include "telemetry/can/spray_bar.h"
#include "telemetry/types.h"

namespace plantscale::telemetry::can {

// Open nozzles as the bar acknowledged them, per-nozzle fault codes
// (plantscale_nozzles_t::FAULT_*: a silent bar is FAULT_NO_ANSWER on every
// nozzle, any reported nozzle fault FAULT_STUCK) and the fail-safe flag.
NozzleBar ToNozzleBar(const SprayBarStatus& status);

}  // namespace plantscale::telemetry::can
