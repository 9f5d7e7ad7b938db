#pragma once
// What the season archive (maps/archive.h) stores about one run, read from
// the export's input: the run id, vehicle, crop profile, start and end time,
// distance and the agronomic figures (review/agronomy.h definitions).
//
//  - run id: the first 16 hex digits of SHA-256 over the input's first
//    64 KiB (a log's first events: its run_started, run_config and first
//    messages), so exporting the same log again names the same run, also
//    while the log is still growing;
//  - from an LCM log (replayed into review::RunModel, as the report does): start
//    and end are the first and last message's time, distance the odometry's,
//    vehicle and crop profile the file stems of the run_config event's
//    profiles ("" when the log has none), figures from review::Agronomy;
//  - from a map or a simulator folder: no times, vehicle or distance;
//    figures from the map's plants (review::AddPlantFigures).

#include <filesystem>
#include <string>

#include "maps/archive.h"
#include "maps/crop_map.h"

namespace plantscale::app {

std::string RunIdOf(const std::filesystem::path& input);

// `input` is an LCM log. Throws telemetry::LogError when unreadable.
maps::ArchiveRun ArchiveRunFromLog(const std::filesystem::path& log);
// `input` is a map file or simulator folder already loaded as `map`.
maps::ArchiveRun ArchiveRunFromMap(const std::filesystem::path& input, const maps::CropMap& map);

// ISO 8601 UTC of a microsecond Unix time.
std::string IsoUtc(int64_t utime);

}  // namespace plantscale::app
