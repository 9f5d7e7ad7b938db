#pragma once
// The ground's shift between two frames with no features and no odometry
// (issue 38), from either of two bird's-eye views in the vehicle frame,
// `cell_m` per pixel, phase-correlated (Hann window, the cross spectrum
// divided by its magnitude to the power `whiten`, the peak placed by
// parabolas or Gaussians):
// - kSoil (GroundShiftOptions::Soil()): the soil's own texture (clods,
//   stones, glints) on the ground, the plants cut out. The soil lies on the
//   plane the camera's height is calibrated to, so the shift has the
//   ground's scale whatever the plants' heights; it fails where a canopy
//   closes over the soil or the soil has no texture (invalid, or the
//   plant masks stand in: `plants_fallback_height_m`).
// - kPlants: the plant masks on the plane at plant height. Plants that
//   merge, split or slide between frames change their contours, and with
//   them the dominant points the feature search pairs, but little of their
//   mass. Plant matter above or below the plane moves faster or slower on
//   it than the ground (its scale is (H − h)/(H − z), 0.7 % per centimetre
//   on the field camera), so the shift reads short or long.
// It is the feature search's prior where the wheels are absent or lie, and
// the motion a frame coasts on when the search does not lock.
//
// The turn between frames comes from the view's near and far halves,
// correlated apart: a turn ψ moves the ground across by −ψ·y at a distance
// y ahead, so the halves' across shifts differ by ψ times the distance
// between their centres. The camera's bounce does not enter that
// difference (a change of pitch moves the ground across by ∝ x·y, which
// sums to zero over a view centred across; a roll or a height change moves
// both halves alike). On `field` the turn reads to 0.09° a frame
// (session 33), half the features' own error (0.19°), and it finds the 1°
// turns that kept the feature search from locking.
//
// The camera's bounce moves the whole view along by about a centimetre
// from frame to frame (0.004 rad of pitch at 1.5 m ahead). The same halves'
// along shifts give the change of pitch (measure_pitch), which comes out of
// the ground's translation; the feature search sees the same bounce, so its
// features must be placed with the pitch too (GroundShift::pitch_rad,
// WithPitch): session 32 took the bounce out of the prior alone and locked
// fewer frames. A roll moves the ground across alike everywhere and stays
// in the translation (docs/results/2026-11-27-visual-motion.md, sessions
// 31–34).
//
// The view is limited to `max_range_m` ahead of the nearest ground seen.

#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <memory>
#include <string>

#include "engine/common/options.h"
#include "engine/geometry/camera_model.h"

namespace plantscale::motion {

// What is correlated (see above).
enum class GroundShiftSource { kPlants, kSoil };

struct GroundShiftOptions {
  GroundShiftSource source = GroundShiftSource::kPlants;
  double plane_height_m = 0.0;  // the plane the masks are warped onto (kSoil: 0)
  double cell_m = 0.008;        // bird's-eye pixel
  double max_half_width_m = 1.0;  // across, each side of the camera
  double max_range_m = 1.6;     // along, from the nearest ground seen
  // The cross spectrum divided by its magnitude to this power: 1 phase
  // correlation (every spatial frequency weighs alike), 0 plain correlation.
  double whiten = 1.0;
  // The peak placed to a fraction of a cell by a parabola through the
  // logarithms of it and its neighbours (a Gaussian) instead of through
  // the values. Soil() only: a parabola draws the soil's smooth peak
  // towards whole cells, which read a 1° turn 10 % short on the halves of
  // a synthetic bed (GroundShift tests).
  bool gaussian_peak = false;
  // The correlation's peak below this: no shift (a view that changed
  // altogether; consecutive field frames give 0.1–0.3, two unrelated
  // views of scattered plants 0.06, GroundShift tests).
  double min_response = 0.08;
  // A shift beyond this fraction of the view: no shift (the peak wrapped).
  double max_shift_fraction = 0.25;
  // The peak less than this many times the runner-up shift's value (the
  // highest beyond the peak's own lobe): no shift. Two shifts that explain
  // the views about equally well mean the views share too little (a narrow
  // view the vehicle crosses most of between frames) or the ground repeats
  // (a roller's pattern). Tuning seeds 1–2, --prior image: the lowest ratio on field,
  // long, treatment, B, C, D, lettuce-fast and cabbage-wide 2.6–6.9, on
  // testbed (the masks standing in) 1.9; on the paper's first set-up (a
  // 0.32 m view, 0.25 m a frame) half of the peaks are below 1.21.
  double min_peak_ratio = 2.0;
  double min_plant_fraction = 0.002;  // of the view; less: no shift
  // kSoil: the plant mask closed by `soil_close_px`, each plant filled to
  // its convex hull and grown by `soil_plant_margin_px` is cut out, and the
  // soil's brightness less its mean over `soil_detrend_m` is correlated
  // (the illumination's gradient and the vehicle's shadow are fixed to the
  // camera).
  int soil_close_px = 10;
  int soil_plant_margin_px = 3;
  double soil_detrend_m = 0.12;
  double min_soil_fraction = 0.3;  // of the view; less: no shift
  // kSoil: where the soil gives no shift (a closed canopy, soil without
  // texture), the plant masks on the plane at this height stand in (a
  // second estimator, shown every frame so that its previous view is ready).
  // Negative: none.
  double plants_fallback_height_m = -1.0;
  // The turn from the near and far halves of the view: both halves' peaks
  // above `min_response` and their across shifts within this of the whole
  // view's, else no turn (ψ = 0, the whole view's shift as the
  // translation). Soil() only: the plant masks' halves gave turns that
  // cost the `treatment` preset locked frames (tuning seeds 1–3: 67 → 61
  // of 87).
  bool measure_turn = false;
  double max_half_disagreement_m = 0.024;
  // The camera's change of pitch from the halves' along shifts (with the
  // turn: measure_turn on; kSoil only). A pitch change Δθ moves a ground
  // point y ahead of the camera's foot along by Δθ·(H² + y²)/H on the
  // nominal camera's view, so the far half moves further than the near
  // one, and the ground's translation is the view's shift less that. Both
  // halves' along shifts must lie within max_half_disagreement_m of the
  // whole view's. On `field` the bounce puts 12 mm on a frame's shift
  // (pitch 0.3° sd); the change reads to 1.6–1.9 mrad rms against a true
  // 4.1 mrad sd (tuning seeds 1–8, session 34), and the shift's error falls
  // to 7.5 mm. The along shifts are read on the views that lost each
  // other's holes (mask_both_views), the across ones on the views as they
  // are.
  // Soil() only: the features the shift is the prior of must then be
  // placed with the pitch too (GroundShift::pitch_rad).
  bool measure_pitch = false;
  // The halves' difference reads a small bias (a mean of 0.36 mrad a frame
  // against the truth's 0.14 on tuning seeds 1–8; cause not traced). A
  // camera's bounce about its mount has no mean change, so the measured
  // changes' running mean (this weight a frame) is taken out.
  double pitch_bias_weight = 0.05;
  // GroundShift::pitch_rad, the changes summed, keeps this share a frame
  // and returns the rest to level, so that the sum of the changes' errors
  // stays bounded on a long run (1: a random walk, 12 mrad in 100 frames).
  double pitch_hold = 0.97;
  // kSoil: each view also loses the other's plants, carried over by the
  // shift found, and is correlated again. The holes cut for the plants move
  // with the plants, faster than the ground, and pulled the peak with them:
  // on `field` the soil read 0.8 % long over a run, 0.06 % with this
  // (session 33); on a synthetic bed of 15 cm plants 0.21 → 0.07 mm a frame.
  // Soil() only.
  bool mask_both_views = false;

  OptionErrors Validate() const;
  // The soil's texture on the ground, its spectrum less whitened (0.7): the
  // texture's finest detail is near the sensor's noise, and full phase
  // correlation let that noise place two of 116 peaks 10–17 cm off on
  // held-out field sequences.
  static GroundShiftOptions Soil();
};

struct GroundShift {
  bool valid = false;
  // The ground's motion from the previous frame to this one, in the vehicle
  // frame: a ground point p moves to R(psi_rad)·p + t_m. Without a turn
  // measured (turn_valid false) ψ = 0 and t_m is the view's shift.
  Eigen::Vector2d t_m{0.0, 0.0};
  double psi_rad = 0.0;
  bool turn_valid = false;
  // The camera's pitch (down) from the previous frame to this one
  // (measure_pitch); t_m is then the ground's, the pitch's apparent shift
  // taken out. Invalid: 0, and t_m holds it.
  double pitch_change_rad = 0.0;
  bool pitch_valid = false;
  // The camera's pitch against its mount's, the changes summed
  // (pitch_hold): place this frame's features with the tilt plus this, so
  // that they move as the ground's translation says (measure_pitch; else 0).
  double pitch_rad = 0.0;
  GroundShiftSource source = GroundShiftSource::kPlants;  // what gave the shift
  double response = 0.0;  // the correlation's peak (above 1 possible when whiten < 1)
  double peak_ratio = 0.0;  // the peak over the runner-up shift's (min_peak_ratio)
  std::string reason;  // why not valid
};

class GroundShiftEstimator {
 public:
  // Throws InvalidOptionsError for invalid options, DataError when the
  // camera sees no ground.
  GroundShiftEstimator(const GroundShiftOptions& options, const geometry::CameraModel& camera);

  // `mask`: CV_8UC1 of the camera's size, plant > 0. The shift from the
  // previous mask given (invalid for the first). Throws DataError for
  // another size or type.
  GroundShift Update(const cv::Mat& mask);
  // `image` the frame (CV_8UC1 grey or CV_8UC3 BGR), `mask` its plants as
  // above: kSoil correlates the soil's texture, kPlants the mask alone.
  // Invalid (and the previous view forgotten) when less than
  // `min_soil_fraction` of the view is soil: a closed canopy.
  // With `plants_fallback_height_m` ≥ 0 the plant masks stand in where
  // the soil gives no shift (`source` says which did).
  GroundShift Update(const cv::Mat& image, const cv::Mat& mask);
  // Forget the previous mask (a gap in the frames).
  void Reset();
  // Whether a shift of `expected_t_m` (vehicle frame, e.g. the previous
  // frame's motion or the wheels') lies within what the view can measure:
  // max_shift_fraction of it across and along. A vehicle that crosses more
  // of a narrow view between frames leaves too little of it in both, and a
  // peak found there is another shift's.
  bool CanMeasure(const Eigen::Vector2d& expected_t_m) const;

  // The bird's-eye view of `mask` (CV_32FC1, 0..1; row r at y = y0 + (r + ½)·cell).
  cv::Mat BirdsEye(const cv::Mat& mask) const;
  // The soil's bird's-eye view on the ground: brightness less its local
  // mean, 0 where plants are (CV_32FC1); `soil_fraction` the share of the
  // view that is soil.
  cv::Mat SoilView(const cv::Mat& image, const cv::Mat& mask, double& soil_fraction,
                   cv::Mat* soil_weight = nullptr) const;
  double x0_m() const { return x0_; }
  double y0_m() const { return y0_; }

 private:
  GroundShiftOptions options_;
  int image_width_ = 0, image_height_ = 0;
  double x0_ = 0.0, y0_ = 0.0;
  double camera_height_m_ = 0.0;  // above the view's plane
  double pitch_bias_rad_ = 0.0;   // the measured changes' running mean
  double pitch_rad_ = 0.0;        // GroundShift::pitch_rad
  cv::Size size_;
  cv::Mat to_image_;  // 3×3: bird's-eye pixel → OpenCV image coordinates
  cv::Mat window_, half_window_, previous_, previous_weight_;
  std::unique_ptr<GroundShiftEstimator> plants_fallback_;
  cv::Mat BirdsEyeInput(const cv::Mat& mask) const;  // checked, plant 255
  // kPlants: the mask's bird's-eye view, or empty (the previous view
  // forgotten) when it holds too little plant matter.
  cv::Mat PlantView(const cv::Mat& mask);
  // kPlants: the mask's view kept as the previous one, nothing correlated
  // (the fallback while the soil gives the shift).
  void Remember(const cv::Mat& mask);
  GroundShift Correlated(cv::Mat view, cv::Mat weight);  // weight: the soil's (kSoil) or empty
  // The shift of `current` against `previous`, both multiplied by `window`.
  cv::Point2d Windowed(const cv::Mat& previous, const cv::Mat& current, const cv::Mat& window,
                       double& response, double* ratio = nullptr) const;
  // The turn and the pitch change from the view's near and far halves.
  struct ViewPair {
    const cv::Mat& previous;
    const cv::Mat& current;
  };
  void MeasureHalves(const ViewPair& for_turn, const ViewPair& for_pitch, GroundShift& shift);
};

// `camera` with its tilt raised by `pitch_rad` (GroundShift::pitch_rad).
geometry::CameraModel WithPitch(const geometry::CameraModel& camera, double pitch_rad);

}  // namespace plantscale::motion
