#pragma once
// The vehicle's own camera as a motion source: the frame-to-frame planar
// motion of the crop's contour features (feature_tracker.h, our variant of
// Sanchiz & Pla's correspondence) turned into the vehicle's forward speed
// and yaw rate with their covariance, for the pipeline to weigh against the
// wheel odometry (pipeline.h) and to stand in for it when the wheels spin,
// stall, read a wrong scale or stop reporting.
//
// The search is centred on the motion the caller expects (the pipeline:
// the crop grid's own motion over the last frames, which the plants hold
// whatever the wheels read): with 5–6 cm of travel between frames and plant
// contours whose dominant points lie 2–5 cm apart, the smoothed previous
// motion alone puts a wrong neighbour as near as the right one.
//
// A frame pair that does not give a trustworthy motion makes the estimate
// invalid with the reason (no features, a blurred or covered frame, all
// features new, too few matches, a motion no smooth continuation of the
// prior); the caller then carries on with the wheels.

#include <cstdint>
#include <span>
#include <string>

#include "engine/common/options.h"
#include "engine/geometry/camera_model.h"
#include "engine/motion/feature_tracker.h"
#include "engine/motion/features.h"
#include "engine/vision/blobs.h"

namespace plantscale::motion {

struct VisualOdometryOptions {
  FeatureOptions features;
  TrackerOptions tracker;
  // Frames further apart than this are not paired (the motion between them
  // is not smooth enough to search around the prior).
  double max_frame_gap_s = 0.3;
  int min_matches = 6;                 // fewer: invalid
  double max_residual_rms_m = 0.008;   // the matches' rms residual beyond this: invalid
  // σ of the prior's rotation over one frame (the wheels' turn rate): weighs
  // it against the fitted rotation.
  double prior_psi_sd_rad = 0.15 * M_PI / 180.0;
  // Floors of the estimate's σ: the contour features' own wander, which the
  // residual of one frame pair understates (field preset, seed 1: the
  // camera's speed is off the wheels' by 0.03 m/s rms per frame pair).
  double min_speed_sd_m_s = 0.03;
  double min_yaw_rate_sd_rad_s = 0.03;

  OptionErrors Validate() const;
};

// The crop's features and our tracker for a crop whose leaf tips stand
// `leaf_height_m` high at radius `leaf_radius_m` (the crop profile's).
VisualOdometryOptions VisualOdometryFor(double leaf_radius_m, double leaf_height_m);

// The search around a prior as the vehicle's camera needs it: the prior's gate
// and the residual gate a few millimetres (5–6 cm of travel per frame, the
// wheels' prior good to a few per cent), blunter dominant points kept
// (more features; the gate, not the sharpness, keeps them apart), and 5 %
// of the features in view matched enough to lock (of 150–250 contour
// features per frame most are lobes that merge, split or slide).
void UsePriorSearch(TrackerOptions& tracker, FeatureOptions& features);

struct VisualMotion {
  bool valid = false;
  std::string reason;          // why not valid
  int64_t utime = 0;           // the frame's capture
  double dt_s = 0.0;           // since the previous frame
  double speed_m_s = 0.0;      // forward, vehicle frame
  double yaw_rate_rad_s = 0.0; // counter-clockwise
  double speed_sd_m_s = 0.0;
  double yaw_rate_sd_rad_s = 0.0;
  int features = 0;
  int matches = 0;
  double residual_rms_m = 0.0;
};

class VisualOdometry {
 public:
  // Throws InvalidOptionsError. The camera is copied.
  VisualOdometry(const geometry::CameraModel& camera, const VisualOdometryOptions& options);

  // The blobs (contours traced) of a frame captured at utime, and the
  // vehicle's expected forward speed and yaw rate since the previous frame.
  // `camera_pitch_rad`: the camera's pitch against its mount's at this
  // frame (GroundShift::pitch_rad, the bounce), which the features are
  // placed with.
  const VisualMotion& Update(int64_t utime, std::span<const vision::Blob> blobs,
                             double prior_speed_m_s, double prior_yaw_rate_rad_s,
                             double camera_pitch_rad = 0.0);
  // The same from features already extracted.
  const VisualMotion& UpdateFeatures(int64_t utime, std::span<const Feature> features,
                                     double prior_speed_m_s, double prior_yaw_rate_rad_s);
  const VisualMotion& last() const { return last_; }
  const FeatureTracker& tracker() const { return tracker_; }
  const VisualOdometryOptions& options() const { return options_; }

 private:
  void Invalid(const std::string& why);

  VisualOdometryOptions options_;
  geometry::CameraModel camera_;
  FeatureExtractor extractor_;
  FeatureTracker tracker_;
  VisualMotion last_;
  int64_t previous_utime_ = -1;
};

}  // namespace plantscale::motion
