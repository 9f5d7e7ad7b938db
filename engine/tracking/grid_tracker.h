#pragma once
// The crop-grid tracker (thesis chs. 4 and 6): an extended Kalman filter on
// the grid state (t_x, Y, Ψ) — or (t_x, Y, Ψ, r̄, l̄) when the grid spacings
// are estimated — predicted at the odometry rate by differential-drive dead
// reckoning (eq. 4.3; the 50 Hz parent node of §4.6) and corrected at the
// frame rate by the vision node's pseudo-observation: the information of all
// matched plant features compressed into one (eqs. 4.73–4.78), after
// parallel validation (§6.2.2), χ² gating (eq. 6.7) and one-to-one
// nearest-neighbour association (eq. 6.6).
//
// Beyond the thesis (whose filter was about 2× overconfident, table 5.22):
// each plant's own offset from its grid position (planting error, lean,
// growth) is the same in every frame that sees it, so it is not white noise.
// With `plant_offsets` the filter carries that offset as a state for every
// plant in view (a prior of `plant_offset_sd_m`), so a plant seen in fifty
// frames counts once, and the covariance stays honest.
//
// This is the public face; the parts, each in its own file (the map with
// the thesis's equations: docs/design.md, "The tracker's parts"):
//   tracker_options.h     the options          tracker_report.h  what it reports
//   state_layout.h        the state's blocks   kalman_filter.h   predict, update
//   process_model.h       eq. 4.3's A and Q    inputs.h          odometry, frames
//   observation_model.h   the plant point      plant_point_model.h  on the state
//   strip_model.h         merged-blob strip    height_from_size.h   δh from size
//   association.h         gating, matching     pseudo_observation.h the update
//   loss_policy.h         loss and recovery    initialiser.h     the start
// Private types shared by the parts: grid_tracker_internal.h.

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "engine/geometry/camera_model.h"
#include "engine/geometry/centroid_height.h"
#include "engine/geometry/grid_model.h"
#include "engine/tracking/feature.h"
#include "engine/tracking/initialiser.h"
#include "engine/tracking/inputs.h"
#include "engine/tracking/kalman_filter.h"
#include "engine/tracking/loss_policy.h"
#include "engine/tracking/height_from_size.h"
#include "engine/tracking/slip_guard.h"
#include "engine/tracking/spacing_check.h"
#include "engine/tracking/tracker_options.h"
#include "engine/tracking/tracker_report.h"

namespace plantscale::tracking {

class GridTracker {
 public:
  // Throws InvalidOptionsError.
  GridTracker(const geometry::CameraModel& camera, const TrackerOptions& options);

  // Dead reckoning: measured wheel speeds over the period ending at utime.
  InputStatus AddOdometry(int64_t utime, double left_m_s, double right_m_s);
  // The same with each wheel speed's σ as a fraction of it (another
  // source's, e.g. the camera's motion standing in for the wheels;
  // AddOdometry uses wheel_sd_fraction).
  InputStatus AddOdometry(int64_t utime, double left_m_s, double right_m_s, double sd_fraction);
  // Vision: the features of a frame captured at utime with this image size.
  // UpdateAtCapture then CatchUp.
  FrameReport ProcessFrame(int64_t utime, int image_width_px, int image_height_px,
                           std::span<const Feature> features);
  // The update alone, leaving the mean where the grid was at the frame's
  // capture: a frame captured before the newest odometry (the camera's
  // latency, odometry that arrived while it was segmented) is compared with
  // the grid at capture, and what else reads the same frame (classifying and
  // placing its blobs) must read the grid there too. `held_lag()` is true
  // until CatchUp (or the next odometry sample, which catches up first).
  FrameReport UpdateAtCapture(int64_t utime, int image_width_px, int image_height_px,
                              std::span<const Feature> features);
  // Drives the mean forward over the lag UpdateAtCapture held back, to the
  // newest odometry's time. Nothing when none is held.
  void CatchUp();
  bool held_lag() const { return held_lag_; }
  // Start tracking from a known state (tests, hand initialisation).
  void Initialise(int64_t utime, const geometry::GridState& state,
                  const geometry::Matrix5d& covariance);
  void Reset();

  TrackerMode mode() const { return mode_; }
  int64_t utime() const { return utime_; }
  // The current grid state; r̄ and l̄ are the fixed values in the 3-state filter.
  geometry::GridState state() const;
  // Covariance of (t_x, Y, Ψ, r̄, l̄); zero rows for fixed spacings.
  geometry::Matrix5d covariance() const;
  // Distance driven along the rows since initialisation: the l̄ increments of
  // every reference shift plus the change of Y (§4.1.3).
  double forward_distance_m() const { return loss_.forward_distance_m(filter_.x()(1)); }
  int lines_passed() const { return loss_.lines_passed(); }
  // The grid once the vehicle has driven `distance_m` further at its
  // current wheel speeds with no update: the dead reckoning's prediction
  // (eq. 4.3) and its process noise, with the odometry scale's and the
  // bounce's uncertainty, in increments of `step_m` (the wheels' noise is
  // per increment, as the odometry's: one long step would overstate it).
  // Where the plants now in view will stand when the spray bar reaches
  // them, had no frame come since. With calibration states, the covariance
  // is the grid's given the calibration (its share, a fixed bias of every
  // frame, taken out). The filter is not changed.
  GridAhead PredictAhead(double distance_m, double step_m) const;
  int plant_offset_states() const { return static_cast<int>(filter_.plants().size()); }
  // The planter's spread as the plants show it (tracker_report.h).
  using PlantSpread = tracking::PlantSpread;
  const PlantSpread& measured_plant_spread() const { return spread_; }
  // The calibration states (pitch, roll, height, focal) and their
  // covariance; zero when not modelled (TrackerOptions::CalibrationStates).
  Eigen::Vector4d calibration_estimate() const;
  Eigen::Matrix4d calibration_covariance() const;
  // Where plant (m, n) of the current grid stands (vehicle frame, on its
  // axis): its grid position plus its own offset when it has one.
  Eigen::Vector2d PlantPosition(int m, int n) const;
  // The same with only part of its own offset: `weight` (across, along)
  // scales δ before it is added to the grid position.
  Eigen::Vector2d PlantPosition(int m, int n, const Eigen::Vector2d& weight) const;
  // Covariance of plant (m, n)'s own offset (δx across, δy along the rows);
  // none when the plant has no offset state.
  std::optional<Eigen::Matrix2d> PlantOffsetCovariance(int m, int n) const;
  // Plant (m, n)'s centroid height above the crop's (δh, TrackerOptions::
  // plant_heights); none when the plant has no such state.
  std::optional<double> PlantHeightOffset(int m, int n) const;
  // The row spacing the frames measure disagrees with the crop profile's
  // (spacing_check.h), as of the last update; none when it agrees or is not
  // yet known. The first such frame's report carries it as the event.
  const std::optional<SpacingMismatch>& row_spacing_mismatch() const { return spacing_check_.current(); }
  // Ground distance per measured wheel distance (1 + k); 1 when not estimated.
  double odometry_scale() const { return filter_.OdometryScale(); }
  // The forward ground speed dead-reckoned with: the last accepted wheel
  // speeds, past the slip guard, times the scale.
  double ground_speed_m_s() const {
    return 0.5 * (wheels_.left_m_s() + wheels_.right_m_s()) * filter_.OdometryScale();
  }
  const SlipGuard& slip_guard() const { return wheels_.slip_guard(); }
  const TrackerOptions& options() const { return options_; }
  const geometry::GridModel& model() const { return model_; }
  // Where blob centroids are located (TrackerOptions::crop_radius_m); null
  // when they stay on the virtual plane. Classifiers comparing blobs with
  // this tracker's predictions locate them the same way (FeaturesFromBlobs).
  const geometry::CentroidHeights* centroid_heights() const {
    return heights_ ? &*heights_ : nullptr;
  }

 private:
  // Offers the frame to the initialiser; on success the state starts
  // there with the initial covariance. False while still initialising.
  bool InitialiseFrom(int64_t utime, const std::vector<Feature>& valid, FrameReport& report);
  // A dead-reckoning step of the filter (nothing but the distance while
  // not tracking).
  void Predict(const WheelStep& step);
  void PredictTo(int64_t utime);
  // Reference shifts (eq. 4.6) as plant lines pass the bottom of the view.
  void ShiftReference(FrameReport& report);
  // Process noise on r̄ and l̄ only when plant lines enter or leave the view.
  void NoteLinesInView(const std::vector<geometry::GridPlant>& in_view);
  // Association, the update and height from size on one frame's features.
  void Update(std::span<const Feature> features, FrameReport& report);
  void CheckLost(int64_t utime, FrameReport& report);

  geometry::CameraModel camera_;
  TrackerOptions options_;
  geometry::GridModel model_;
  std::optional<geometry::CentroidHeights> heights_;
  GridInitialiser initialiser_;
  TrackerMode mode_ = TrackerMode::kInitialising;
  GridFilter filter_;
  DeadReckoning wheels_;
  HeightFromSize sizes_;
  LossPolicy loss_;
  PlantSpread spread_;
  SpacingCheck spacing_check_;
  bool spacing_reported_ = false;  // the mismatch event was sent (once until Reset)
  int64_t utime_ = -1;          // time of the state
  WheelIncrement since_frame_;  // wheel motion since the last frame (initialisation)
  Eigen::Vector3d caught_up_ = Eigen::Vector3d::Zero();  // (t_x, Y, Ψ) at utime_ while held
  bool held_lag_ = false;       // the mean stands at the last frame's capture (CatchUp)
  int lines_in_view_ = -1;      // the last plant line in view (counting passed lines)
  int first_line_in_view_ = 0;
};

}  // namespace plantscale::tracking
