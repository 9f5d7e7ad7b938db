#pragma once
// The grid tracker's options (GridTracker, grid_tracker.h): which states it
// carries, its noise, gating and loss thresholds, each with why it has the
// value it has. Validate() names every option out of range.

#include "engine/common/options.h"
#include "engine/tracking/initialiser.h"
#include "engine/tracking/slip_guard.h"

namespace plantscale::tracking {

enum class ObservationSpace {
  kGround,  // centroids on the virtual ground plane (ours)
  kImage,   // pixel centroids with R projected from the ground (thesis eq. 4.28)
};

struct TrackerOptions {
  bool estimate_spacing = true;  // 5-state (thesis §4.1.2) or 3-state (§4.1.1)
  bool plant_offsets = true;     // per-plant offset states (grid_tracker.h says why)
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
  // Initial σ of r̄, l̄ when estimated. r̄'s is how precisely the drill's
  // row spacing is known (the crop profile's row_spacing_sd_m, 5 mm for a
  // product run); 0.03 here for a tracker told nothing.
  double row_spacing_sd_m = 0.03;
  double plant_spacing_sd_m = 0.03;
  // Process noise on r̄, l̄ per line entering or leaving (§4.1.2). The
  // thesis adds it because the mean over the plants in view changes as
  // plants come and go; with plant_offsets each plant's own deviation is a
  // state, so this only carries the bed's true drift (a planter's slipping
  // ground wheel: about 1 mm per metre, some 2 lines in and 2 out).
  double spacing_step_sd_m = 0.001;
  // The row spacing the frames measure against the profile's
  // (spacing_check.h): d² = (r̂ − r₀)²/(V₀ − P) beyond this is a
  // mismatch, reported once (FrameReport::row_spacing_mismatch). 10.83:
  // χ²₁'s 99.9 % point, as d² is tested on every update. 0: not checked
  // (and never with fixed spacings).
  double spacing_check_chi2 = 10.83;
  // The fractional sd of the scale a camera off its calibration puts on
  // the distances it sees (tilt, height, focal; ProductTrackerOptions from
  // the vehicle's calibration_sd): the check allows r̄ that much more.
  double spacing_check_scale_sd = 0.0;
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

}  // namespace plantscale::tracking
