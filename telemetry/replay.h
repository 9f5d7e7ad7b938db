#pragma once
// Republishes an LCM log with its original timing (scaled by a speed), from
// a start offset, on the channels matching a regex. A log cut off mid-event
// replays up to its last whole event and reports where it stopped.

#include <cstdint>
#include <filesystem>
#include <string>

#include "engine/common/options.h"
#include "telemetry/transport.h"

namespace plantscale::telemetry {

struct ReplayOptions {
  double speed = 1.0;           // 2: twice as fast as recorded
  double start_s = 0.0;         // skip this much of the log (from its first event)
  std::string channels = ".*";  // ECMAScript regex matched against whole names

  // Keys: "speed", "start_s", "channels".
  OptionErrors Validate() const;
};

struct ReplaySummary {
  int64_t events_read = 0;
  int64_t published = 0;
  double log_seconds = 0.0;  // span of the published events in the log
  double wall_seconds = 0.0;
  std::string error;  // LogReader::error(), empty when the log was whole
};

// Throws InvalidOptionsError, LogError (cannot open) or TransportError.
ReplaySummary Replay(const std::filesystem::path& log, Transport& transport,
                     const ReplayOptions& options);

}  // namespace plantscale::telemetry
