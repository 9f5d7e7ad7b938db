#include "telemetry/can/nozzle_bar.h"

#include <algorithm>
#include <plantscale_lcmtypes/plantscale_nozzles_t.hpp>

namespace plantscale::telemetry::can {

NozzleBar ToNozzleBar(const SprayBarStatus& s) {
  NozzleBar bar;
  const size_t n = s.nozzle_faults.size();
  bar.open.resize(n);
  bar.fault.resize(n);
  const bool silent =
      !s.heard || std::any_of(s.reasons.begin(), s.reasons.end(), [](const std::string& r) {
        return r.rfind("no heartbeat", 0) == 0 || r.rfind("waiting", 0) == 0;
      });
  for (size_t i = 0; i < n; ++i) {
    bar.open[i] = ((s.applied_mask >> i) & 1u) != 0;
    if (silent) {
      bar.fault[i] = plantscale_nozzles_t::FAULT_NO_ANSWER;
    } else if (s.nozzle_faults[i] != NozzleFault::kNone) {
      bar.fault[i] = plantscale_nozzles_t::FAULT_STUCK;
    } else {
      bar.fault[i] = plantscale_nozzles_t::FAULT_NONE;
    }
  }
  bar.failsafe = s.failsafe;
  return bar;
}

}  // namespace plantscale::telemetry::can
