#pragma once
// `plantscale evaluate log`: scores a vehicle log recorded on the simulator
// (`simulate --publish --log`) against the truth it carries, with the same
// definitions as `evaluate treatment` and `evaluate tracking`, so that what
// the vehicle process did on a run and what the evaluations measure on the
// same preset and seed can be compared.
//
// The field is rebuilt from the log's run_config event (preset, seed,
// length: the simulator is deterministic in them, app/config/run_config.h).
//  - Treatment: the logged shots give each nozzle's open and close times,
//    which are the bar's commands; a SimulatedBar turns them into shots with
//    the true valve latency along the true pose track
//    (PLANTSCALE_SIM_TRUTH_POSE), and ScoreSpray scores them against the
//    field's plants in TreatmentScoreRegion, which starts from where the
//    chain first classified: the first PLANTSCALE_GRID message with the
//    grid tracked (tracking or dead-reckoning mode).
//  - Tracking: every PLANTSCALE_GRID estimate against the
//    PLANTSCALE_SIM_TRUTH of its frame (ScoreGrid, InitialisedOnTruth,
//    FinishTrackingMetrics), past the same settle distances along the true
//    path driven.
// What a log cannot tell is left out (LogEvaluation says which): the pixel
// confusion (no images or labels), the scheduler's ticks and the plant
// records; only the run's own first initialisation (no fresh-start probes);
// the tracker's forward distance is its grid position Y unwrapped over the
// plant lines passed while tracked. Messages the publisher's bandwidth
// budget dropped (grid and truth are not essential) are simply not scored.

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "app/config/run_config.h"
#include "evaluation/tracking_eval.h"
#include "evaluation/treatment_eval.h"

namespace plantscale::app {

struct LogEvalOptions {
  std::filesystem::path log;
  // Where the run's preset is read; empty: the run_config's config_dir when
  // it exists, else DefaultConfigDir().
  std::filesystem::path config_dir;
  double settle_m = TrackingEvalOptions{}.settle_m;  // as evaluate tracking
  double spacing_settle_m = TrackingEvalOptions{}.spacing_settle_m;
};

// The messages of the log that were scored.
struct LogMessages {
  int64_t events = 0;
  int grid = 0, truth = 0, truth_pose = 0, nozzles = 0, shots = 0;
  int grid_without_truth = 0;  // tracked, past settle_m, but their frame's truth was dropped
  int undecodable = 0;
};

struct LogEvaluation {
  std::string log;
  SimRunConfig run;
  std::filesystem::path config_dir;  // where the preset was read
  double distance_m = 0.0;           // true path driven, from the start to the last truth pose
  TreatmentMetrics treatment;        // the pixel and tick fields are not known
  TrackingMetrics tracking;
  LogMessages messages;
  std::vector<std::string> problems;  // a log cut off, undecodable messages
  // The vehicle's row_spacing_mismatch events (the bed's row spacing against
  // the crop profile's, at most one a run): when and what it said.
  struct Said {
    int64_t utime = 0;
    std::string text;
  };
  std::vector<Said> row_spacing_events;
};

// The keys of evaluate treatment's metrics a log cannot give (MetricsJson
// keys; the command writes them as null).
const std::vector<std::string>& TreatmentKeysNotInLogs();

// Throws telemetry::LogError naming the log when it cannot be opened or
// holds no whole event; ConfigError naming the log when it has no run_config
// event (not a simulated run's log) or no simulator truth, or when the run's
// preset cannot be loaded.
LogEvaluation EvaluateLog(const LogEvalOptions& options);

}  // namespace plantscale::app
