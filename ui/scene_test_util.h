#pragma once
// Shared set-up of the ui tests: a synthetic run replayed up to a time.

#include "ui/station_timeline.h"
#include "ui/synthetic_run.h"

namespace plantscale::ui::testing {

inline LogTimeline RunUpTo(const SyntheticRunOptions& options, double seconds) {
  LogTimeline timeline(SyntheticRun(options), "");
  timeline.Seek(seconds);
  return timeline;
}

}  // namespace plantscale::ui::testing
