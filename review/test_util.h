#pragma once
// Shared set-up of the review and ui tests: a synthetic run replayed up to a time.

#include "review/log_timeline.h"
#include "review/synthetic_run.h"

namespace plantscale::review::testing {

inline LogTimeline RunUpTo(const SyntheticRunOptions& options, double seconds) {
  LogTimeline timeline(SyntheticRun(options), "");
  timeline.Seek(seconds);
  return timeline;
}

}  // namespace plantscale::review::testing
