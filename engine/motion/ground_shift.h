#pragma once
// The ground's shift between two frames from the plant masks alone, with no
// features and no odometry (issue 38): each mask is warped onto the plane at
// plant height, a bird's-eye view in the vehicle frame, `cell_m` per
// pixel, and the two views are phase-correlated (Hann window, the cross
// spectrum divided by its magnitude, the peak placed by parabolas). Plants that merge, split or slide between frames change
// their contours, and with them the dominant points the feature search
// pairs, but little of their mass: the correlation peak is the motion of
// the plant matter as a whole. It is the feature search's prior where the
// wheels are absent or lie, and the motion a frame coasts on when the
// search does not lock.
//
// Only the translation is measured (the rotation between frames of a
// vehicle following rows is a few milliradians). The view is limited to
// `max_range_m` ahead of the nearest ground seen, where the plants are
// resolved. What limits it (docs/results/2026-11-27-visual-motion.md,
// session 31): the camera's bounce moves the whole view by about a
// centimetre from frame to frame (0.004 rad of pitch at 1.5 m), and plant
// matter above or below the plane moves faster or slower on it than the
// ground (its scale is (H − h)/(H − z), 0.7 % per centimetre here).

#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <string>

#include "engine/common/options.h"
#include "engine/geometry/camera_model.h"

namespace plantscale::motion {

struct GroundShiftOptions {
  double plane_height_m = 0.0;  // the plane the masks are warped onto
  double cell_m = 0.008;        // bird's-eye pixel
  double max_half_width_m = 1.0;  // across, each side of the camera
  double max_range_m = 1.6;     // along, from the nearest ground seen
  // The cross spectrum divided by its magnitude to this power: 1 phase
  // correlation (every spatial frequency weighs alike), 0 plain correlation.
  double whiten = 1.0;
  // The correlation's peak below this: no shift (a view that changed
  // altogether; consecutive field frames give 0.1–0.3, two unrelated
  // views of scattered plants 0.06, GroundShift tests).
  double min_response = 0.08;
  // A shift beyond this fraction of the view: no shift (the peak wrapped).
  double max_shift_fraction = 0.25;
  double min_plant_fraction = 0.002;  // of the view; less: no shift

  OptionErrors Validate() const;
};

struct GroundShift {
  bool valid = false;
  Eigen::Vector2d t_m{0.0, 0.0};  // the ground's displacement, previous → current frame, vehicle frame
  double response = 0.0;
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
  // Forget the previous mask (a gap in the frames).
  void Reset() { previous_.release(); }

  // The bird's-eye view of `mask` (CV_32FC1, 0..1; row r at y = y0 + (r + ½)·cell).
  cv::Mat BirdsEye(const cv::Mat& mask) const;
  double x0_m() const { return x0_; }
  double y0_m() const { return y0_; }

 private:
  GroundShiftOptions options_;
  int image_width_ = 0, image_height_ = 0;
  double x0_ = 0.0, y0_ = 0.0;
  cv::Size size_;
  cv::Mat to_image_;  // 3×3: bird's-eye pixel → OpenCV image coordinates
  cv::Mat window_, previous_;
};

}  // namespace plantscale::motion
