#pragma once
// `plantscale evaluate treatment`: drives a simulator preset through
// segmentation, the grid tracker and the treatment chain (classifier,
// treatment map, nozzle scheduler) into a simulated spray bar, then scores
// the shots against plant truth (treatment_score.h) and the classified
// pixels against the label images (thesis tables 7.5–7.8). The thesis's own
// chain (its tracker, adaptive threshold, whole bounding-box footprints, a
// 50-pixel size filter and a 95 % gate) runs on the same frames as the
// baseline. Optionally sweeps the classifier's two parameters into an MRROC.

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "app/config/profiles.h"
#include "engine/pipeline/pipeline.h"
#include "engine/sim/simulator.h"
#include "engine/tracking/grid_tracker.h"
#include "engine/treatment/treatment_system.h"
#include "engine/vision/segmenter.h"
#include "evaluation/engine_used.h"
#include "evaluation/mrroc.h"
#include "evaluation/odometry_fault.h"
#include "evaluation/treatment_score.h"

namespace plantscale::app {

struct TreatmentEvalOptions {
  sim::SimulatorOptions sim;  // the simulated field and vehicle (the engine never reads it)
  // What the engines are configured from (required): a crop and a vehicle
  // profile (treatment: ProductTreatmentOptions of them, then any changes),
  // and the error of the engine's calibration (signs per seed).
  std::optional<Profiles> profiles;
  CalibrationError calibration_error;
  std::string calibration_error_text;  // as given (the table quotes it); empty: none
  int seeds = 5;  // sim.seed, sim.seed + 1, ... (ForEachSeed)
  vision::SegmenterOptions segmenter;  // ours (the thesis's chain: ThesisSegmenterOptions)
  pipeline::LearnedOptions learned;    // ours: the crop profile's learned model, if any
  treatment::TreatmentOptions treatment;
  double true_valve_latency_s = -1.0;  // the simulated valves' latency; < 0: as scheduled
  bool baseline_thesis = false;
  // Each frame reaches the pipeline this long after its capture, after the
  // odometry samples up to then (the camera's and segmentation's latency);
  // at most the tracker's max_frame_lag_s less a frame.
  double frame_lag_s = 0.0;
  bool mrroc = false;
  double costs_ratio = 1.0;  // Φ for the MRROC operating point
  // Changes to our tracker's options (ProductTrackerOptions of the
  // profiles), for trying them; none: the product's.
  std::function<void(tracking::TrackerOptions&)> adjust_tracker;
  // Faulty wheel odometry over one stretch (odometry_fault.h), and the
  // camera's motion as the pipeline's second motion source (ours only).
  OdometryFault odometry_fault;
  bool visual_motion = false;

  OptionErrors Validate() const;
};

// The engines' camera of run `seed`: the vehicle's calibration with the
// crop's virtual plane, off by the calibration error with the seed's signs.
geometry::CameraOptions TreatmentEngineCamera(const TreatmentEvalOptions& options, uint64_t seed);
// The thesis's chain (§8.2): whole bounding boxes, table 7.2's size filter
// of the sequence named `preset` (in pixels of `camera`).
treatment::TreatmentOptions ThesisTreatmentOptions(const std::string& preset,
                                                   const geometry::CameraOptions& camera);

struct TreatmentMetrics {
  int crop_plants = 0, crop_hits = 0;
  double crop_hit_rate = 0.0;
  int weeds = 0, weed_hits = 0;
  double weed_hit_rate = 0.0;
  int weeds_clear = 0;
  double weed_hit_rate_clear = 0.0;  // weeds not under a crop's leaves
  // Weeds touching a crop's outline (SprayScore::weeds_touching): hit, and
  // hit with the crop's root dry.
  int weeds_touching = 0;
  double weed_hit_rate_touching = 0.0, weed_hit_rate_touching_crop_dry = 0.0;
  double placement_bias_along_m = 0.0, placement_bias_across_m = 0.0;  // to the root
  double placement_rms_along_m = 0.0, placement_rms_across_m = 0.0;
  double placement_rms_m = 0.0;  // the larger of the two
  double centre_bias_along_m = 0.0, centre_bias_across_m = 0.0;  // to root + lean
  double centre_rms_along_m = 0.0, centre_rms_across_m = 0.0;
  double treated_area_fraction = 0.0;
  // Pixels (trapezoid between the wheels, doubt band out, frames classified):
  // fraction of true crop / weed pixels labelled C, W or S.
  double crop_as_crop = 0.0, crop_as_weed = 0.0, crop_as_soil = 0.0;
  double weed_as_crop = 0.0, weed_as_weed = 0.0, weed_as_soil = 0.0;
  // crop_as_weed by why the pixel's blob was labelled W: not classified (no
  // feature), under the size filter, outside every association region,
  // another rule, or a merged blob's part left to no crop (split_part;
  // split_clipped when the blob was cut by the image border). They sum to
  // crop_as_weed.
  double crop_as_weed_no_decision = 0.0, crop_as_weed_small = 0.0,
         crop_as_weed_unassociated = 0.0, crop_as_weed_other = 0.0,
         crop_as_weed_split_part = 0.0, crop_as_weed_split_clipped = 0.0;
  double crop_pixel_rate = 0.0;  // = crop_as_crop
  // Of the true crop / weed pixels segmented as plant (C or W), the fraction
  // labelled C: thesis table 7.9's TPR and FPR, which leave out what
  // segmentation lost to soil.
  double crop_pixel_rate_of_plant = 0.0, weed_pixel_fpr_of_plant = 0.0;
  int frames_classified = 0;
  int ticks = 0, ticks_fail_safe = 0, shots = 0, map_resets = 0, plants_recorded = 0;
  int plants_confirmed = 0;  // records that are plants, not passing detections (PlantRecord::confirmed)
};

// One evaluation: its figures and what it was run with (its JSON and table,
// treatment_writer.h, need nothing else).
struct TreatmentEvaluation {
  std::string preset;
  uint64_t first_seed = 0;  // the runs' seeds: NthSeed(first_seed, 0 … seeds − 1)
  int seeds = 0;
  EngineUsed engine;
  OdometryFault odometry_fault;
  bool visual_motion = false;
  double costs_ratio = 1.0;  // of the MRROC operating point
  std::string mode;
  double distance_m = 0.0;
  TreatmentMetrics ours;
  std::optional<TreatmentMetrics> thesis;
  std::optional<classify::Mrroc> mrroc;
  classify::MrrocPoint operating_point;  // for costs_ratio
  classify::MrrocPoint nearest_corner;   // thesis table 7.2
  std::vector<std::string> example_why;  // a few plant records' `why`
  std::vector<MissedCrop> missed_crops;  // ours, every seed (seed_index: 0-based run)
  // Ours over the faulty stretch (with an odometry fault): the spray of the
  // plants the bar passed while the fault lasted, and the odometry samples
  // the camera stood in for over the run.
  std::optional<TreatmentMetrics> fault_stretch;
  int camera_substitutions = 0;
};

TreatmentEvaluation EvaluateTreatment(const TreatmentEvalOptions& options);

// How a run's spraying is scored (shared with evaluate log). The plants
// whose whole life under the camera and the bar fell inside the run: from
// past the far edge of the view where the chain first classified (the
// vehicle's true y then), to behind the bar at the end (`last_y`, the
// vehicle's last true y).
SprayScoreRegion TreatmentScoreRegion(const sim::Simulator& sim, double first_classified_y,
                                      double last_y, const treatment::TreatmentOptions& options);
// The spray metrics (hits, placement, treated area) of a score; the pixel
// and chain counts are left zero.
TreatmentMetrics SprayMetrics(const SprayScore& score);

}  // namespace plantscale::app
