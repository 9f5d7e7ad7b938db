#pragma once
// A run's LCM log (what the vehicle published) as a CropMap for export: the
// newest revision of every map tile (PLANTSCALE_MAP_TILES), the newest
// observation of every plant (PLANTSCALE_PLANTS) and the run's provenance.
// The log is the only input, so `plantscale export run.lcmlog` works on any
// machine that has the log, live or long after the run.

#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "maps/crop_map.h"

namespace plantscale::app {

struct LogMapReport {
  int64_t events = 0;
  int tiles = 0;             // distinct tiles (newest revision kept)
  int plants = 0;            // distinct plant ids
  int bad_messages = 0;      // undecodable tile or plant messages (skipped)
  std::vector<std::string> problems;  // bad messages, a cut-off log: what and where
};

// Progress: (events read, events in the log).
using LogProgress = std::function<void(int64_t done, int64_t total)>;

// Throws telemetry::LogError when the file cannot be opened or is not an LCM
// log at all, and maps::DataError when the log holds no map tiles and no
// plants or tiles of differing resolution. A log cut off mid-event gives the
// map up to its last whole event, with the cut named in `report.problems`.
maps::CropMap CropMapFromLog(const std::filesystem::path& log, LogMapReport& report,
                             const LogProgress& progress = {});

}  // namespace plantscale::app
