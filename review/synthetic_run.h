#pragma once
// A synthetic vehicle run as an LCM event list: every channel the station
// shows (grid estimate and truth, pose, plants, map tiles, nozzles, health,
// thumbnail, odometry, events) for a straight bed driven with a gentle
// zig-zag. Until the tracker, classifier and treatment map publish for real
// this is what the golden tests and the benchmarks render; seeded, so the
// same options give the same bytes. Faults can be injected (heartbeat stop,
// vehicle restart, NaN message, foreign channel).

#include <cstdint>
#include <filesystem>
#include <optional>
#include <utility>
#include <vector>

#include "telemetry/log.h"

namespace plantscale::review {

struct SyntheticRunOptions {
  double length_m = 10.0;
  double speed_m_s = 0.5;
  double frame_rate_hz = 12.5;
  double row_spacing_m = 0.475;
  double plant_spacing_m = 0.45;
  double zigzag_amplitude_m = 0.04;
  double zigzag_period_m = 8.0;
  double weeds_per_m = 2.0;
  int nozzles = 6;
  double cell_m = 0.02;  // map resolution
  int tile_cells = 64;
  // A tile row is sent once the vehicle is this far past its end (negative:
  // before it). The vehicle sends a row once its spray bar has passed it, and
  // its bed frame drifts from the pose drawn: 1.0-3.1 m behind the pose on
  // the field preset (0.1-4.75 km).
  double map_lag_m = -0.9;
  uint32_t seed = 1;
  int64_t start_utime = 1'700'000'000'000'000;
  std::optional<double> heartbeat_stops_at_s;  // no PLANTSCALE_HEALTH after this
  std::optional<double> restart_at_s;          // new boot time, sequences from 0
  std::optional<double> nan_grid_at_s;         // one grid message with a NaN offset
  std::vector<std::pair<int, int>> missing_crops;  // (row −1..1, plant line from 0 at y = 0.5 m) not planted
};

std::vector<telemetry::LogEvent> SyntheticRun(const SyntheticRunOptions& options);
// Throws telemetry::LogError.
void WriteSyntheticLog(const std::filesystem::path& path, const SyntheticRunOptions& options);

}  // namespace plantscale::review
