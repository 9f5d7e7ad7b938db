#pragma once
// `plantscale evaluate motion`: Sanchiz & Pla's correspondence and motion
// recovery on a simulator preset, scored against truth. Per seed, one
// sequence of `frames` images (the paper's 30); for each method (the
// paper's, ours): the rate of correct correspondences, frame-to-frame
// rotation and translation errors, drift of the composed pose without
// odometry, and the row fit of the mosaic (§5).

#include <string>
#include <vector>

#include "engine/motion/feature_tracker.h"
#include "engine/motion/features.h"
#include "engine/motion/ground_shift.h"
#include "engine/motion/mosaic.h"
#include "engine/sim/simulator.h"
#include "engine/vision/segmenter.h"
#include "evaluation/row_fit.h"

namespace plantscale::app {

struct MotionMethodOptions {
  motion::FeatureOptions features;
  motion::TrackerOptions tracker;
  double mosaic_plane_height_m = 0.0;  // plane the labels are placed on in the mosaic
};

// kNone: the smoothed previous motion (no odometry at all); kWheels: the
// motion the wheel odometry reports since the previous frame (as the
// vehicle's pipeline does, with the simulator's faulty wheels: scale error,
// slip); kImage: the ground's shift between the two frames, the soil's
// texture or the plant masks phase-correlated (motion/ground_shift.h: images
// only, no odometry at all). With a prior
// the search is the prior-gated one, and a frame that does not lock
// coasts on the prior.
enum class MotionPrior { kNone, kWheels, kImage };
const char* MotionPriorName(MotionPrior p);  // "none", "wheels", "image"

struct MotionEvalOptions {
  sim::SimulatorOptions sim;
  int seeds = 3;                    // seeds sim.seed, sim.seed + 1, ... (ForEachSeed)
  int frames = 30;                  // the paper's sequences are 30 images
  double match_tolerance_m = 0.02;  // a match is correct on the same plant within this
  double mosaic_resolution_m = 0.01;
  vision::SegmenterOptions segmenter;
  MotionMethodOptions paper, ours;  // defaults: PaperMethod(), OursMethod()
  motion::RowFitOptions rows;
  // What ours searches each frame around (MotionPrior); the pose still
  // composes the camera's motion only. σ of the prior's rotation per frame
  // (the wheels' turn, or the ground shift's; where the ground shift
  // measured no turn, none):
  MotionPrior prior = MotionPrior::kNone;
  double prior_psi_sd_rad = 0.15 * M_PI / 180.0;
  // kImage: the soil's texture by default, the plant masks on ours' feature
  // plane standing in where the soil gives no shift; the plant masks alone
  // (GroundShiftOptions{}) are warped onto ours' feature plane.
  motion::GroundShiftOptions ground_shift = motion::GroundShiftOptions::Soil();
  // kImage with the soil: the features' locked translation scaled by the
  // soil's distance over theirs (pipeline::VisualScale, learnt over the
  // sequence from `soil_scale_min_distance_m` on, ±20 %). The contour
  // features are placed on the crop profile's plane, the soil lies on the
  // ground the camera's height is calibrated to (session 33: the features
  // read 1–1.5 % short on `field`).
  bool soil_scale = true;
  double soil_scale_min_distance_m = 0.1;
  // Ours' features placed with the camera's pitch from frame to frame, read
  // off the soil view's near and far halves (GroundShiftOptions::measure_pitch,
  // GroundShift::pitch_rad): the camera's bounce moved them by about 12 mm
  // a frame on `field`. With kImage the soil's shift gives it (and takes it
  // out of the prior's translation); with kWheels a soil estimator of its
  // own reads it (the prior stays the wheels'). kNone (the paper's own
  // set-ups) never: nothing there is searched around.
  bool camera_pitch = true;
  // The table shows the paper's method beside ours (it is always evaluated,
  // and always in the JSON).
  bool paper_in_table = false;

  OptionErrors Validate() const;
};

// The published method: features on the ground plane (z_vc = v) and the
// paper's stages and noise. Ours: the feature plane at the crop's rim
// height and our stages (feature_tracker.h).
MotionMethodOptions PaperMethod();
MotionMethodOptions OursMethod(const sim::SimulatorOptions& sim);

struct MotionMethodEvaluation {
  std::string method;
  int pairs = 0, locked_pairs = 0;
  int matches = 0, correct_matches = 0;
  // Matches with a feature on no plant (none within 2 px): a stone, a clod
  // or a shadow's edge segmented as plant matter. Such a feature is scored
  // by its ground point: right when both lie on the ground within the
  // tolerance (a stone keeps its place; a feature on the vehicle's own
  // shadow does not).
  int matches_on_ground = 0;
  double correct_correspondence_rate = 0.0;
  double rotation_rmse_deg = 0.0;
  double translation_rmse_m = 0.0;
  double drift_cm_per_m = 0.0;  // mean over seeds of |T − T_true| / distance
  // The signed parts of T − T_true along and across the first frame's
  // forward axis, per metre, mean over seeds: a systematic heading error
  // shows as a mean across, a wrong scale or speed as a mean along.
  double drift_along_cm_per_m = 0.0;
  double drift_across_cm_per_m = 0.0;
  int rows_fitted = 0;          // rows found, summed over seeds
  double row_fit_rms_m = 0.0;   // mean over fitted rows
  double row_angle_deg = 0.0;   // mean between neighbouring rows
  double row_spacing_m = 0.0;   // mean between neighbouring rows at the map centre
  std::vector<double> row_rms_m;       // every fitted row
  std::vector<double> row_spacings_m;  // every neighbouring pair
  double ms_per_frame = 0.0;           // correspondence + motion only
  // With the image prior: the frame pairs whose ground shift was valid,
  // and its error against the true translation over them; the pairs with
  // a turn measured too, and its error over them.
  int prior_valid_pairs = 0;
  double prior_translation_rmse_m = 0.0;
  int prior_turn_pairs = 0;
  double prior_rotation_rmse_deg = 0.0;
  // With the soil's scale: its ratio at each sequence's end, mean over
  // sequences (1 when it was never learnt).
  double soil_scale = 1.0;
};

// One evaluation: its figures and what it was run with (its JSON and table,
// motion_writer.h, need nothing else).
struct MotionEvaluation {
  std::string preset;
  bool paper_in_table = false;  // MotionEvalOptions'

  int seeds = 0, frames = 0;
  double distance_m = 0.0;  // per sequence, mean
  double true_row_spacing_m = 0.0;
  MotionPrior prior = MotionPrior::kNone;
  motion::GroundShiftSource ground_shift_source = motion::GroundShiftSource::kSoil;  // kImage
  bool soil_scale = false;  // the soil's scale applied
  bool camera_pitch = false;  // ours' features placed with the soil's pitch
  MotionMethodEvaluation paper, ours;
};

MotionEvaluation EvaluateMotion(const MotionEvalOptions& options);

}  // namespace plantscale::app
