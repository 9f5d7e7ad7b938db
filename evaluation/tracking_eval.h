#pragma once
// `plantscale evaluate tracking`: drives a simulator preset, segments every
// frame, feeds odometry at its own rate and the blobs at the frame rate to
// the grid tracker, and scores it against the simulator's grid truth.
// The thesis's own tracker (3-state fixed grid, image-plane update with
// R projected from the ground, constant process noise per frame, adaptive
// threshold segmentation) runs on the same frames as the baseline
// (docs/simulator.md: calibrated presets).

#include <Eigen/Core>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "app/config/profiles.h"
#include "engine/sim/simulator.h"
#include "engine/tracking/grid_tracker.h"
#include "engine/vision/segmenter.h"
#include "evaluation/engine_used.h"
#include "evaluation/odometry_fault.h"

namespace plantscale::app {

// What lateral errors are scored against: the planted grid (every frame) or
// each line of plants the vehicle passes (thesis §8.1, `--reference
// plant-lines`; TrackingMetrics::plant_line_lateral_*).
enum class TrackingReference { kGrid, kPlantLines };
const char* Name(TrackingReference reference);  // "grid", "plant-lines"

struct TrackingEvalOptions {
  sim::SimulatorOptions sim;       // the simulated field and vehicle (the engine never reads it)
  // What the engines are configured from (required): a crop and a vehicle
  // profile, and the error of the engine's calibration (signs per seed).
  std::optional<Profiles> profiles;
  CalibrationError calibration_error;
  std::string calibration_error_text;  // as given (the table quotes it); empty: none
  int seeds = 10;                  // sim.seed, sim.seed + 1, ... (ForEachSeed)
  double spacing_offset_m = 0.0;   // ours starts with both spacings this far off the crop profile's
  bool baseline_thesis = false;
  // Ours locates centroids on the virtual plane, not at the crop's
  // centroid heights (to measure what the height model is worth).
  bool centroids_on_virtual_plane = false;
  // Ours carries the camera's tilt, height and focal length (the vehicle's
  // calibration_sd) as consider states beside the roll
  // (TrackerOptions::calibration_scale_consider), which the product's
  // profile does not (`--scale-consider`, for measuring).
  bool calibration_scale_consider = false;
  // Per-frame errors of ours (one CSV row per scored frame), when set.
  std::ostream* trace = nullptr;
  double settle_m = 1.0;           // errors count from this far past initialisation
  double spacing_settle_m = 5.0;   // spacing errors count from this far
  double init_probe_interval_m = 5.0;  // a fresh initialisation is tried this often
  int init_probe_max_frames = 25;
  // Faulty wheel odometry over one stretch (odometry_fault.h), and the
  // camera's motion as the pipeline's second motion source.
  OdometryFault odometry_fault;
  bool visual_motion = false;
  // With kPlantLines the metrics' lateral figures are those at the lines of
  // plants (the grid's kept in TrackingEvaluation::grid_lateral_rmse_m).
  TrackingReference reference = TrackingReference::kGrid;

  OptionErrors Validate() const;
};

// The engines of one run (seed): the camera they use (the vehicle's
// calibration with the crop's virtual plane, off by the calibration error
// with the seed's signs), our tracker's options and the thesis tracker's.
// Built from options.profiles and calibration_error only, never from
// options.sim.
struct TrackingEngine {
  CalibrationError calibration_error;  // the seed's draw
  geometry::CameraOptions camera;
  tracking::TrackerOptions ours, thesis;
};
TrackingEngine TrackingEngineOf(const TrackingEvalOptions& options, uint64_t seed);

// One run (seed) of one tracker: every run counts, a run that never
// started or lost the grid included.
// The tracker found the bed's row spacing disagreeing with the crop
// profile's (FrameReport::row_spacing_mismatch): where, and the truth there.
struct RowSpacingEvent {
  double distance_m = 0.0;         // driven (truth) since the run began
  double since_start_m = 0.0;      // driven since the tracker's first start
  double true_row_spacing_m = 0.0; // the simulator's, where it was found
  tracking::SpacingMismatch mismatch;
};

struct TrackingRun {
  uint64_t seed = 0;
  CalibrationError calibration_error;  // drawn for this seed
  bool started = false;                // the grid was ever tracked
  int frames = 0, frames_lost = 0, losses = 0;
  double lateral_rmse_m = 0.0;  // NaN when no frame was scored
  double nees_in_bounds_fraction = 0.0;
  std::vector<RowSpacingEvent> row_spacing_events;  // ours's, at most one a run
  // The tracker's calibration states (tilt, roll, height, focal), when it
  // carries them: the estimate and its sd 20 m after the first start and at
  // the end of the run. NaN when not carried or not reached.
  struct CalibrationEstimate {
    Eigen::Vector4d value = Eigen::Vector4d::Constant(std::nan(""));
    Eigen::Vector4d sd = Eigen::Vector4d::Constant(std::nan(""));
  };
  CalibrationEstimate calibration_at_20m, calibration_at_end;
};

struct TrackingMetrics {
  // Frames scored: every frame past settle_m after the run's first start,
  // those on which the grid was lost (until it recovers) included with the
  // error of the estimate held, outside the NEES bounds.
  int frames = 0;
  int frames_lost = 0;      // of `frames`
  int runs_not_started = 0; // runs in which the grid was never tracked
  int frames_tracking = 0;  // frames in which the filter was tracking
  int updates = 0;
  int losses = 0;
  int row_spacing_events = 0;  // runs whose row spacing disagreed with the crop profile's
  double lateral_rmse_m = 0.0;
  double lateral_mean_m = 0.0;
  double forward_mean_m = 0.0;  // signed mean error of Y (modulo l̄)
  double bearing_rmse_deg = 0.0;
  double forward_drift_cm_per_m = 0.0;      // mean over runs, signed
  double forward_drift_abs_max_cm_per_m = 0.0;
  double row_spacing_error_m = 0.0;    // RMS past spacing_settle_m
  double plant_spacing_error_m = 0.0;
  double row_spacing_mean_error_m = 0.0;  // signed: the bias within the RMS
  double plant_spacing_mean_error_m = 0.0;
  double nees_in_bounds_fraction = 0.0;  // (t_x, Y, Ψ) inside the two-sided 95 % χ²₃ interval
  double nees_mean = 0.0;
  Eigen::Vector3d normalised_error2 = Eigen::Vector3d::Zero();  // mean e²/σ² of t_x, Y, Ψ (1 ideal)
  double lateral_sd_mean_m = 0.0;        // the filter's own σ(t_x)
  double init_success_rate = 0.0;
  double init_frames_p95 = 0.0;
  int init_trials = 0;
  double mean_matched = 0.0;
  std::vector<double> run_lateral_rmse_m;
  std::vector<TrackingRun> runs;  // per seed, in seed order
  // The planter's spread the tracker measured over every run
  // (GridTracker::measured_plant_spread, pooled).
  tracking::GridTracker::PlantSpread plant_spread;
  std::vector<double> run_forward_drift_cm_per_m;
  // The thesis's field protocol (§8.1, fig. 8.1; `--reference plant-lines`):
  // the offset scored once at each line of plants the vehicle passes, against
  // the trail read from the mean root position of that line's plants (so it
  // holds the plants' irregularity as well as the tracker's error).
  int plant_lines_scored = 0;
  double plant_line_lateral_rmse_m = 0.0;
  double plant_line_lateral_mean_m = 0.0;
  std::vector<double> run_plant_line_lateral_rmse_m;
  // Over the faulty stretch (with --odometry-fault): frames, of them those
  // tracking, the lateral RMSE of those, the grid's losses (it was
  // tracking, then lost) and the forward error's RMS (modulo l̄).
  int fault_frames = 0;
  int fault_frames_tracking = 0;
  int fault_losses = 0;
  double fault_lateral_rmse_m = 0.0;
  double fault_forward_rmse_m = 0.0;
  int camera_substitutions = 0;  // odometry samples the camera stood in for
};

// One evaluation: its figures and what it was run with (its JSON and table,
// tracking_writer.h, need nothing else).
struct TrackingEvaluation {
  std::string preset;
  int seeds = 0;
  double distance_m = 0.0;  // driven per run
  double spacing_offset_m = 0.0;
  EngineUsed engine;
  OdometryFault odometry_fault;
  bool visual_motion = false;
  TrackingReference reference = TrackingReference::kGrid;
  // The lateral RMSE against the planted grid of ours and of the thesis's
  // tracker (0 without it), whatever the reference.
  double grid_lateral_rmse_m = 0.0, thesis_grid_lateral_rmse_m = 0.0;
  // The planter's spread: what the crop profile told the engine, and the
  // simulator's own (placement jitter and lean; scoring only).
  double planter_sd_profile_m = 0.0;
  double planter_sd_generator_m = 0.0;
  TrackingMetrics ours;
  std::optional<TrackingMetrics> thesis;
};

TrackingEvaluation EvaluateTracking(const TrackingEvalOptions& options);

// How a frame's grid estimate is scored against its truth (shared with
// evaluate log): errors of t_x, Y (modulo the true plant spacing) and Ψ, and
// their NEES under the filter's covariance of (t_x, Y, Ψ), inside or not the
// two-sided 95 % χ²₃ interval.
struct GridErrors {
  double lateral_m = 0.0, forward_m = 0.0, bearing_rad = 0.0;
  double nees = 0.0;
  bool nees_in_bounds = false;
  Eigen::Vector3d normalised2 = Eigen::Vector3d::Zero();  // e²/σ² of t_x, Y, Ψ
  double lateral_sd_m = 0.0;                              // the filter's σ(t_x)
};
GridErrors ScoreGrid(const geometry::GridState& estimate, const Eigen::Matrix3d& covariance,
                     const geometry::GridState& truth);
// The errors alone (t_x, Y modulo the true plant spacing, Ψ), for an estimate
// the filter no longer vouches for (a lost grid): ScoreGrid without NEES.
GridErrors GridErrorsOf(const geometry::GridState& estimate, const geometry::GridState& truth);
// An initialisation found the right grid: within a quarter of a spacing
// across and along, and 2° in bearing.
bool InitialisedOnTruth(const geometry::GridState& estimate, const geometry::GridState& truth);
// Turns the sums in `m` (squared errors in the RMSE fields, errors in the
// means', per-run lists filled) into the metrics.
void FinishTrackingMetrics(TrackingMetrics& m, int spacing_frames,
                           const std::vector<double>& init_frames, int init_trials,
                           int init_successes);

}  // namespace plantscale::app
