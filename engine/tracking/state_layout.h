#pragma once
// Where each block of the grid tracker's state vector sits (GridTracker):
//
//   core         (t_x, Y, Ψ) and, when the spacings are estimated, the
//                spacing block (r̄, l̄): thesis §4.1.1 (3 states) or
//                §4.1.2 (5 states), at geometry::GridState's indices
//   k            the wheels' scale error (estimate_odometry_scale)
//   bounce       the camera's pitch, roll and height when the bounce
//                persists (a Gauss–Markov state; a bounce that does not
//                persist is a nuisance block appended for one update)
//   calibration  the calibration's error: pitch, roll, height, focal
//   ── head() ──
//   plants       per plant in view, (δx, δy) or (δx, δy, δh): its own
//                offset from its grid position and its centroid height,
//                in the order the plants came into view (PlantOffset)
//
// The head's blocks are fixed by the options; the plants' come and go.
// The priors of the blocks are here too, beside the blocks they start.

#include <Eigen/Core>

#include "engine/tracking/tracker_options.h"

namespace plantscale::tracking {

class StateLayout {
 public:
  explicit StateLayout(const TrackerOptions& o)
      : spacing_(o.estimate_spacing),
        scale_(o.estimate_odometry_scale),
        persistent_bounce_(o.model_bounce && o.camera_bounce_correlation_s > 0.0),
        nuisance_bounce_(o.model_bounce && !persistent_bounce_),
        calibration_(o.CalibrationStates()),
        consider_(o.CalibrationStates() && o.calibration_scale_consider),
        plant_states_(o.PlantHeightStates() ? 3 : 2) {}

  // (t_x, Y, Ψ, r̄, l̄) or (t_x, Y, Ψ).
  int core() const { return spacing_ ? 5 : 3; }
  bool spacing() const { return spacing_; }
  // The wheels' scale error k, at core() when estimated.
  bool odometry_scale() const { return scale_; }
  int scale_index() const { return core(); }
  // The camera bounce (pitch, roll, height) as a state that persists.
  bool persistent_bounce() const { return persistent_bounce_; }
  // The bounce as a per-frame nuisance block (model_bounce, not persistent).
  bool nuisance_bounce() const { return nuisance_bounce_; }
  int bounce_index() const { return core() + (scale_ ? 1 : 0); }
  // The calibration's error (pitch, roll, height, focal) when modelled.
  bool calibration() const { return calibration_; }
  int calibration_index() const { return bounce_index() + (persistent_bounce_ ? 3 : 0); }
  // Pitch, height and focal held as Schmidt consider states (never updated).
  bool consider() const { return consider_; }
  // Everything before the plants' own states.
  int head() const { return calibration_index() + (calibration_ ? 4 : 0); }
  // States per plant: δx, δy, then δh (TrackerOptions::PlantHeightStates).
  int plant_states() const { return plant_states_; }

 private:
  bool spacing_;
  bool scale_;
  bool persistent_bounce_;
  bool nuisance_bounce_;
  bool calibration_;
  bool consider_;
  int plant_states_;
};

// A plant carried in the state: grid line m (0: bottom-most in view, moved
// with the reference shifts), row n, and where its δx sits in the state.
struct PlantOffset {
  int m = 0;
  int n = 0;
  int index = 0;  // of δx in the state; δy, then δh (plant_heights), follow
};

// Prior variances of the camera bounce (pitch, roll, height).
inline Eigen::Vector3d BouncePrior(const TrackerOptions& o) {
  return {o.camera_pitch_sd_rad * o.camera_pitch_sd_rad, o.camera_roll_sd_rad * o.camera_roll_sd_rad,
          o.camera_height_sd_m * o.camera_height_sd_m};
}

// Prior variances of the calibration's error (pitch, roll, height, focal).
inline Eigen::Vector4d CalibrationPrior(const TrackerOptions& o) {
  return {o.calibration_pitch_sd_rad * o.calibration_pitch_sd_rad,
          o.calibration_roll_sd_rad * o.calibration_roll_sd_rad,
          o.calibration_height_sd_m * o.calibration_height_sd_m,
          o.calibration_focal_sd * o.calibration_focal_sd};
}

}  // namespace plantscale::tracking
