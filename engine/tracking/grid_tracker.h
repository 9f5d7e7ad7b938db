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

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "engine/common/options.h"
#include "engine/geometry/camera_model.h"
#include "engine/geometry/centroid_height.h"
#include "engine/geometry/grid_model.h"
#include "engine/tracking/feature.h"
#include "engine/tracking/initialiser.h"
#include "engine/tracking/motion_model.h"
#include "engine/tracking/slip_guard.h"

namespace plantscale::tracking {

class ObservationModel;  // observation_model.h
struct Prediction;
struct StripPrediction;  // observation_model.h

enum class ObservationSpace {
  kGround,  // centroids on the virtual ground plane (ours)
  kImage,   // pixel centroids with R projected from the ground (thesis eq. 4.28)
};

struct TrackerOptions {
  bool estimate_spacing = true;  // 5-state (thesis §4.1.2) or 3-state (§4.1.1)
  bool plant_offsets = true;     // per-plant offset states (see above)
  ObservationSpace space = ObservationSpace::kGround;
  // Camera bounce (pitch, roll, height) moves every feature of a frame
  // together; with model_bounce it is a per-frame nuisance state.
  bool model_bounce = true;
  double camera_pitch_sd_rad = 0.005;
  double camera_roll_sd_rad = 0.0035;
  double camera_height_sd_m = 0.004;
  // How long the bounce lasts. 0: white, a fresh nuisance state each frame.
  // > 0: a first-order Gauss–Markov process with this time constant (a
  // suspension's), kept as a state: bounce that lasts over several frames
  // moves them all alike, so treating it as white is overconfident.
  double camera_bounce_correlation_s = 0.0;
  // How far the camera's calibration may be off (the vehicle profile's
  // camera.calibration_sd): tilt, roll, height and focal length (a
  // fraction). A calibration error moves every feature of every frame the
  // same way, a bounce that never decays: with any of these set it is a
  // state (pitch, roll, height, focal) of that prior and no process noise.
  // What the frames and the wheels cannot tell apart from the grid's own
  // offset, bearing and scale (a roll reads as a lateral offset) stays at
  // its prior, and the grid's covariance carries it, so σ(t_x) covers it;
  // what they can (a roll's shear of the outer rows) is learnt. 0: the
  // calibration is taken as exact.
  double calibration_pitch_sd_rad = 0.0;
  double calibration_roll_sd_rad = 0.0;
  double calibration_height_sd_m = 0.0;
  double calibration_focal_sd = 0.0;
  // Tilt, height and focal length scale the vision's distances, which
  // trade against the wheels' scale k and the spacings: estimated, they
  // drift along that direction (docs/results/2026-11-27-calibration.md).
  // As consider
  // states (Schmidt) they are never updated, so the grid's mean is as if
  // the calibration were exact, but their uncertainty and its correlation
  // with the grid stay in the covariance: σ covers their error. The roll is
  // estimated.
  bool calibration_scale_consider = true;
  bool CalibrationStates() const {
    return calibration_pitch_sd_rad > 0.0 || calibration_roll_sd_rad > 0.0 ||
           calibration_height_sd_m > 0.0 || calibration_focal_sd > 0.0;
  }
  int rows_each_side = 1;      // the bed: rows −k..k
  double row_spacing_m = 0.475;    // r̄: nominal, the fixed value or the initial estimate
  double plant_spacing_m = 0.45;   // l̄
  double row_spacing_sd_m = 0.03;  // initial σ of r̄, l̄ when estimated
  double plant_spacing_sd_m = 0.03;
  // Process noise on r̄, l̄ per line entering or leaving (§4.1.2). The
  // thesis adds it because the mean over the plants in view changes as
  // plants come and go; with plant_offsets each plant's own deviation is a
  // state, so this only carries the bed's true drift (a planter's slipping
  // ground wheel: about 1 mm per metre, some 2 lines in and 2 out).
  double spacing_step_sd_m = 0.001;
  double plant_offset_sd_m = 0.015;  // σ of a plant's persistent offset from its grid position
  // Where a plant's centroid is located wanders as the view of it changes
  // (leaves turn in and out of view, self-shadow, lobes): a random walk of
  // its offset per √m driven, across and along the rows. A fixed offset
  // pushes that wander into r̄ and l̄. Measured on the field preset as the
  // linear trend of each plant's located-minus-true centroid over its
  // passage through the view (about 2.1 m): 8.2 mm across, 18.7 mm along,
  // for a crop 0.112 m tall; the wander is the parallax of its leaves, so
  // for another crop scale these by its height over kOffsetWalkCropHeightM.
  // Along, most of that trend is the parallax of the plant's own height,
  // which the plant_heights states now carry; a walk as large as the trend
  // let the offset soak it up instead, and the height stayed at its prior.
  // The walks' sweep: docs/results/2026-11-26-tracking.md.
  static constexpr double kOffsetWalkCropHeightM = 0.112;
  double plant_offset_walk_across_sd_per_sqrt_m = 0.006;
  double plant_offset_walk_along_sd_per_sqrt_m = 0.006;
  // A plant's own centroid height differs from the crop's (size, lean,
  // leaves): as the plant crosses the view that error moves its located
  // centroid radially from the nadir by p·δh/(H − h), a shift that grows
  // with distance and so is neither white nor a constant offset. With
  // plant_heights each plant's δh is a state beside its offset (only with
  // plant_offsets); the parallax over the frames that see it estimates it.
  bool plant_heights = true;
  double plant_height_sd_m = 0.02;  // measured on the field preset: sd 0.020 m about the mean
  bool PlantHeightStates() const { return plant_offsets && plant_heights; }
  // A plant's size shows in its blob: the inverted hemisphere scales with
  // its leaf span, so a plant s times the crop's mean size has its centroid
  // at s·h_l (h_l: the mean crop's centroid height where its blob lies),
  // and the parallax of that height is most of what moves its located
  // centroid along the rows from frame to frame (field preset, perfect
  // segmentation, after the frame's common shift: sd 8.0 mm at 0.6–0.9 m
  // ahead, 5.6 mm once the radius and lean are regressed out). With
  // height_from_size, each matched blob's equivalent radius ρ = √(A/π)
  // against the running mean ρ̄ of the crop's matched blobs in the same band
  // of image rows gives s = (ρ + e)/(ρ̄ + e), and δh = h_l·(s − 1) is a
  // pseudo-observation of the plant's δh with σ size_height_sd_m per frame.
  // e (size_edge_loss_m) is the rim a blob loses to the notches between
  // leaves and to shaded leaf edges, about the same width on every plant:
  // on the field preset ρ ≈ r − 11 mm (r: leaf-tip radius), so without it
  // s overstates a plant's size. Blobs whose s is outside
  // [1/size_ratio_max, size_ratio_max] are merged or cut and say nothing
  // of the plant's size. Needs PlantHeightStates() and the crop's radius.
  // The sweep of e and σ: docs/results/2026-11-26-tracking.md.
  bool height_from_size = true;
  double size_height_sd_m = 0.006;
  double size_edge_loss_m = 0.03;
  double size_ratio_max = 1.5;
  int size_bands = 8;               // bands of image rows for ρ̄
  int size_min_samples = 30;        // blobs in a band before it observes
  double size_mean_weight = 0.02;   // EMA weight of each blob in its band's ρ̄
  bool HeightFromSize() const { return PlantHeightStates() && height_from_size && crop_radius_m > 0.0; }
  double feature_sd_m = 0.008;       // R_w: centroid noise on the ground, per axis (eq. 4.28)
  // The crop's mean leaf-tip radius and height (a ruler, or the growth
  // stage). When both are set, a blob's centroid is located at the height
  // where the ray through the image centroid of such a plant crosses its
  // axis (geometry/centroid_height.h, thesis §2.3.8's inverted hemisphere),
  // which varies over the view, instead of on the one virtual plane set by
  // eye: that plane's error scales every position and reads as a wrong
  // plant spacing, a forward drift.
  double crop_radius_m = 0.0;
  double crop_height_m = 0.0;
  double pixel_sd_px = 0.5;          // centroid quantisation
  // Dead reckoning (process noise of eq. 4.3).
  double track_width_m = 1.5;
  double wheel_sd_fraction = 0.03;      // σ of a wheel increment / the increment
  // Forward process noise: what the wheel scale k and the slip guard do
  // not model (gradual slip, soil give). Measured: docs/results/2026-11-26-tracking.md.
  double forward_sd_per_sqrt_m = 0.005;  // m per √m driven
  double lateral_sd_per_sqrt_m = 0.002;
  double bearing_sd_per_sqrt_m = 0.003;  // rad per √m
  // The wheels' scale error k (ground distance = (1 + k) × measured) as a
  // state: a tyre's rolling radius is a few per cent off and changes with
  // load and soil, and an unmodelled scale biases every prediction the same
  // way, so the grid lags behind the plants by several millimetres. With
  // the plants located at their true heights the vision measures distance
  // driven, which makes k observable (not so with a virtual plane at the
  // wrong height, whose scale error is the same as k's).
  bool estimate_odometry_scale = true;
  double odometry_scale_sd = 0.05;                 // prior σ of k
  double odometry_scale_step_sd_per_sqrt_m = 0.002;  // random walk of k per √m driven
  // Wheel spin and lock read from the wheels' speeds (slip_guard.h), not
  // from the frames, which would take each frame's bounce and the plants
  // coming into view for a change of speed (tried and not kept:
  // docs/results/2026-11-26-tracking.md).
  SlipGuardOptions slip_guard;
  // Constant process noise per vision frame (thesis eq. 4.2); zero for ours.
  double frame_offset_sd_m = 0.0;
  double frame_forward_sd_m = 0.0;
  double frame_bearing_sd_rad = 0.0;
  // Data association and robustness.
  double gate_chi2 = 5.99;  // eq. 6.7, 95 % for 2 dof
  // A blob whose image box holds the predictions of two or more plants is
  // plants merged in the image (tall neighbours touch in perspective long
  // before they touch on the ground): its centroid lies between them, and
  // inside one's gate it drags that plant's offset by centimetres. Such
  // blobs are not associated, unless fewer than half as many other blobs
  // as plants predicted in view would be left (plants touching everywhere,
  // as on preset A).
  bool skip_merged_features = true;
  // A merged blob whose box holds the predictions of two or more plants of
  // one row and of no other row is those plants touching along the row
  // (late in the season, or tall neighbours in perspective): its centroid
  // lies between them along the row, where their visible areas weigh it,
  // but on the row's line across it. With merged_row_strips it is a
  // measurement of the row's lateral position alone (a strip): the
  // centroid's distance across the row from the mean of those plants'
  // predictions, one degree of freedom gated at strip_gate_chi2, R widened
  // by strip_sd_m for the unequal weights. With strips on, no merged blob
  // (along a row or across rows) is taken as one plant's centroid, even
  // when few others are left. (Taken along the row as well, with a tenth of
  // a plant spacing as its sd, the strips' centroids pulled the grid both
  // ways: docs/results/2026-11-29-unseen-fields.md.) Needs
  // skip_merged_features. Off: the thesis's point features only (with the
  // proviso above).
  bool merged_row_strips = true;
  double strip_gate_chi2 = 3.84;  // 95 % for 1 dof
  double strip_sd_m = 0.01;
  double strip_max_offset_fraction = 0.25;  // of the row spacing (FindStrips)
  // A frame whose point matches cannot observe the grid updates on its
  // strips alone; off, it makes no update (as before), and where plants
  // touch the grid coasts and is lost more often (the figures:
  // docs/results/2026-11-29-unseen-fields.md).
  bool strips_alone = true;
  // A blob smaller than this fraction of the crop's area (π crop_radius_m²,
  // when the crop's radius is set) is a weed or a leaf cut off by shadow,
  // not a crop's centroid: associated with a crop whose own blob missed its
  // gate it drags that plant's offset towards itself, by 10 cm and more on
  // the field preset. Such blobs are not associated (with the same proviso).
  double min_feature_area_fraction = 0.1;
  double edge_margin_px = 8.0;  // predictions nearer the image edge than this are not used
  double max_wheel_speed_m_s = 3.0;
  double max_odometry_gap_s = 0.2;
  double max_frame_lag_s = 0.2;
  double lost_offset_sd_m = 0.06;  // σ(t_x) beyond this: the grid is lost
  double max_coast_s = 3.0;        // no update for this long: the grid is lost
  InitialiserOptions init;

  OptionErrors Validate() const;
};

enum class TrackerMode { kInitialising, kTracking, kLost };
const char* ToString(TrackerMode mode);

// Accepted or refused input, with the reason.
struct InputStatus {
  bool accepted = true;
  std::string reason;
};

struct Association {
  int feature = -1;  // index into the frame's features
  int m = 0;         // grid line (0: bottom-most in view)
  int n = 0;         // row (0: central)
  double gamma2 = 0.0;  // normalised innovation (eq. 6.5)
};

struct FrameReport {
  InputStatus input;
  TrackerMode mode = TrackerMode::kInitialising;
  bool initialised_now = false;
  bool updated = false;
  std::string skipped_reason;  // why no update was made, when it was not
  int predicted = 0;           // grid plants in view
  int matched = 0;
  int strips = 0;              // merged blobs along one row taken for its lateral position
  int lines_shifted = 0;       // reference shifts (eq. 4.6) before this frame's update
  double nis = 0.0;            // stacked normalised innovation squared
  std::vector<Association> associations;
};

// The vision node's compressed measurement (eqs. 4.77–4.78) in square-root
// information form: with each feature's innovation whitened by its R
// (R = C Cᵀ), L stacks C⁻¹ H and r stacks C⁻¹ ν, so that Ĩ = Σ Hᵀ R⁻¹ H =
// LᵀL and ĩ = Σ Hᵀ R⁻¹ ν = Lᵀ r, linearised at the dead-reckoning
// prediction. It is defined even when the features do not observe every
// state on their own, and L's columns are zero outside `support` (the grid,
// the bounce and the matched plants' own states), which the update uses.
struct PseudoObservation {
  Eigen::MatrixXd factor;    // L: 2·(matched features) × state size
  Eigen::VectorXd residual;  // r
  std::vector<int> support;  // the states L touches
};

// The grid predicted ahead by dead reckoning alone (GridTracker::PredictAhead).
struct GridAhead {
  geometry::GridState state;
  geometry::Matrix5d covariance = geometry::Matrix5d::Zero();  // of (t_x, Y, Ψ, r̄, l̄)
};

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
  double forward_distance_m() const { return passed_m_ + initial_forward_m_ - x_(1); }
  int lines_passed() const { return lines_passed_; }
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
  int plant_offset_states() const { return static_cast<int>(offsets_.size()); }
  // The planter's spread as the plants show it (the crop profile's
  // planter_sd_m is a grower's guess): when a plant leaves the view, the
  // square of its offset's estimate on each axis the frames pinned (its
  // variance below half the prior's); the root mean square over the
  // tracker's life, starts and losses included (grid_tracker.cc says why
  // this estimator).
  struct PlantSpread {
    double across_sum2 = 0.0, along_sum2 = 0.0;
    int across = 0, along = 0;
    double across_sd_m() const;  // NaN before any plant
    double along_sd_m() const;
  };
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
  // Ground distance per measured wheel distance (1 + k); 1 when not estimated.
  double odometry_scale() const { return OdometryScale(); }
  // The forward ground speed dead-reckoned with: the last accepted wheel
  // speeds, past the slip guard, times the scale.
  double ground_speed_m_s() const { return 0.5 * (left_m_s_ + right_m_s_) * OdometryScale(); }
  const SlipGuard& slip_guard() const { return slip_guard_; }
  const TrackerOptions& options() const { return options_; }
  const geometry::GridModel& model() const { return model_; }
  // Where blob centroids are located (TrackerOptions::crop_radius_m); null
  // when they stay on the virtual plane. Classifiers comparing blobs with
  // this tracker's predictions locate them the same way (FeaturesFromBlobs).
  const geometry::CentroidHeights* centroid_heights() const {
    return heights_ ? &*heights_ : nullptr;
  }

 private:
  struct PlantOffset {
    int m = 0;
    int n = 0;
    int index = 0;  // of δx in the state; δy, then δh (plant_heights), follow
  };
  int PlantStates() const { return options_.PlantHeightStates() ? 3 : 2; }

  // The frame's refusal (a size not the camera model's, or captured longer
  // before the state than max_frame_lag_s), noted in the report.
  bool RefuseFrame(int64_t utime, int width, int height, FrameReport& report) const;
  // The features with finite values, located on the height map when there
  // is one; the number ignored goes into the report.
  std::vector<Feature> ValidFeatures(std::span<const Feature> features,
                                     FrameReport& report) const;
  // Offers the frame to the initialiser; on success the state starts
  // there with the initial covariance. False while still initialising.
  bool InitialiseFrom(int64_t utime, const std::vector<Feature>& valid, FrameReport& report);

  int core() const { return options_.estimate_spacing ? 5 : 3; }
  // The core grid state, then k when the odometry scale is estimated, then
  // the camera bounce (pitch, roll, height) when it persists.
  bool PersistentBounce() const {
    return options_.model_bounce && options_.camera_bounce_correlation_s > 0.0;
  }
  int BounceIndex() const { return core() + (options_.estimate_odometry_scale ? 1 : 0); }
  // Then the calibration's error (pitch, roll, height, focal) when modelled.
  int CalibrationIndex() const { return BounceIndex() + (PersistentBounce() ? 3 : 0); }
  int head() const { return CalibrationIndex() + (options_.CalibrationStates() ? 4 : 0); }
  Eigen::Vector3d BouncePrior() const;
  Eigen::Vector4d CalibrationPrior() const;
  // Pitch, height and focal calibration states held as consider states.
  bool ConsiderStates() const {
    return options_.CalibrationStates() && options_.calibration_scale_consider;
  }
  void ResetCalibration();
  // The ObservationModel's prediction of plant (m, n) with the persistent
  // bounce's effect and columns added.
  Prediction PredictPlant(const ObservationModel& h, const geometry::GridState& s, int m,
                          int n) const;
  double OdometryScale() const { return options_.estimate_odometry_scale ? 1.0 + x_(core()) : 1.0; }
  // One dead-reckoning step of the head state (core, k, bounce) from `s`:
  // the motion, its transition A and process noise Q (eq. 4.3).
  struct Transition {
    MotionPrediction f;
    Eigen::MatrixXd a, q;
    double bounce_decay = 1.0;
  };
  Transition TransitionFrom(const geometry::GridState& s, double scale, const WheelIncrement& u,
                            double left_sd_m, double right_sd_m, double dt_s) const;
  void Predict(const WheelIncrement& u, double left_sd_m, double right_sd_m, double dt_s);
  void ResetBounce();
  void PredictTo(int64_t utime);
  // No odometry sample for longer than max_odometry_gap_s before utime.
  bool WheelsSilentAt(int64_t utime) const;
  // The odometry-gap bridge's σ of each wheel's increment over dt.
  double BridgeSd(double dt) const;
  void MoveMean(const WheelIncrement& u);  // the mean only (out-of-sequence frames)
  void ShiftReference(FrameReport& report);
  void AddSpacingNoise(int lines_changed);
  void Update(std::span<const Feature> features, FrameReport& report);
  // Update's steps: a plant of the view (index into it) and a feature
  // gated together, with the innovation's γ².
  struct Candidate {
    int plant;
    int feature;
    double gamma2;
  };
  void NoteLinesInView(const std::vector<geometry::GridPlant>& in_view);
  void MarkSkippedFeatures(std::span<const Feature> features,
                           const std::vector<geometry::GridPlant>& in_view);
  Eigen::Matrix2d NewPlantPrior(const Prediction& pred) const;
  Eigen::Matrix2d PredictionCovariance(const Prediction& pred, int offset,
                                       const Eigen::Vector3d& bounce_prior) const;
  std::vector<Candidate> Gate(const ObservationModel& h, const geometry::GridState& s,
                              std::span<const Feature> features,
                              const std::vector<geometry::GridPlant>& in_view,
                              const Eigen::Vector3d& bounce_prior) const;
  static std::vector<Candidate> Associate(std::vector<Candidate> candidates, size_t plants,
                                          size_t features);
  // A merged blob along one row (merged_row_strips): the feature and the
  // plants of the view (indices) its box holds.
  struct Strip {
    int feature;
    std::vector<int> plants;
  };
  // The strip's prediction (observation_model.h) at the current state, its
  // plants ordered along the row; with `nuisance` the bounce's columns are
  // the per-frame nuisance states'. `prior`, when given, gets the offset
  // prior of its plants not yet carried as states.
  StripPrediction PredictStripAt(const ObservationModel& h, const geometry::GridState& s,
                                 const std::vector<geometry::GridPlant>& in_view, const Strip& strip,
                                 bool nuisance, Eigen::Matrix2d* prior = nullptr) const;
  std::vector<Strip> FindStrips(const ObservationModel& h, const geometry::GridState& s,
                                std::span<const Feature> features,
                                const std::vector<geometry::GridPlant>& in_view,
                                const std::vector<Candidate>& matches,
                                const Eigen::Vector3d& bounce_prior) const;
  bool Observable(const std::vector<Candidate>& matches,
                  const std::vector<geometry::GridPlant>& in_view, FrameReport& report) const;
  void WhitenedUpdate(const ObservationModel& h, const geometry::GridState& s,
                      std::span<const Feature> features,
                      const std::vector<geometry::GridPlant>& in_view,
                      const std::vector<Candidate>& matches, const std::vector<Strip>& strips,
                      const Eigen::Vector3d& bounce_prior, FrameReport& report);
  // Applies z (eqs. 4.73–4.74); returns the normalised innovation squared.
  double Apply(const PseudoObservation& z);
  // TrackerOptions::height_from_size: observes the δh of the plants matched
  // to `features` (plant, feature) from their blobs' areas, then adds those
  // areas to their bands' means.
  struct SizeMatch {
    int m, n, feature;
  };
  void ObserveHeightsFromSize(std::span<const Feature> features,
                              std::span<const SizeMatch> matches);
  void DropOffsetsOutOfView(const std::vector<geometry::GridPlant>& in_view);
  void AddToSpread(const PlantOffset& o);  // a plant leaving the view (measured_plant_spread)
  int OffsetIndex(int m, int n) const;
  int AddOffset(int m, int n);
  void CheckLost(int64_t utime, FrameReport& report);

  geometry::CameraModel camera_;
  TrackerOptions options_;
  geometry::GridModel model_;
  std::optional<geometry::CentroidHeights> heights_;
  GridInitialiser initialiser_;
  TrackerMode mode_ = TrackerMode::kInitialising;
  Eigen::VectorXd x_;  // core state, then (δx, δy) per plant offset
  Eigen::MatrixXd p_;
  std::vector<PlantOffset> offsets_;
  PlantSpread spread_;
  std::vector<bool> skipped_;  // Update scratch: feature j is not associated
  std::vector<bool> merged_;   // ... and j's box holds two or more predictions
  // Per band of image rows: running mean equivalent radius √(A/π) of
  // matched crop blobs, and how many went in (height_from_size).
  std::vector<double> band_radius_m_;
  std::vector<int> band_samples_;
  int64_t utime_ = -1;      // time of the state
  int64_t last_wheels_utime_ = -1;  // newest odometry sample offered, accepted or not
  SlipGuard slip_guard_;
  double left_m_s_ = 0.0;   // last accepted wheel speeds (past the slip guard)
  double right_m_s_ = 0.0;
  bool have_speeds_ = false;
  WheelIncrement since_frame_;  // wheel motion since the last frame (initialisation)
  Eigen::Vector3d caught_up_ = Eigen::Vector3d::Zero();  // (t_x, Y, Ψ) at utime_ while held
  bool held_lag_ = false;       // the mean stands at the last frame's capture (CatchUp)
  int64_t last_update_utime_ = -1;
  int lines_in_view_ = -1;
  int first_line_in_view_ = 0;
  int lines_passed_ = 0;
  double passed_m_ = 0.0;
  double initial_forward_m_ = 0.0;
  bool was_lost_ = false;
  double distance_at_loss_m_ = 0.0;
  double dr_since_loss_m_ = 0.0;  // dead-reckoned while not tracking
};

}  // namespace plantscale::tracking
