#include "engine/motion/visual_odometry.h"

#include <algorithm>
#include <cmath>

#include "engine/motion/ground_shift.h"

namespace plantscale::motion {

OptionErrors VisualOdometryOptions::Validate() const {
  OptionErrors e = Prefixed("features", features.Validate());
  for (OptionError& t : Prefixed("tracker", tracker.Validate())) e.push_back(std::move(t));
  if (tracker.method != MotionMethod::kOurs) e.push_back({"tracker.method", "must be ours"});
  RequirePositive(e, "max_frame_gap_s", max_frame_gap_s);
  if (min_matches < 2) e.push_back({"min_matches", "must be >= 2"});
  RequirePositive(e, "max_residual_rms_m", max_residual_rms_m);
  RequirePositive(e, "prior_psi_sd_rad", prior_psi_sd_rad);
  RequirePositive(e, "min_speed_sd_m_s", min_speed_sd_m_s);
  RequirePositive(e, "min_yaw_rate_sd_rad_s", min_yaw_rate_sd_rad_s);
  return e;
}

VisualOdometryOptions VisualOdometryFor(double leaf_radius_m, double leaf_height_m) {
  VisualOdometryOptions o;
  const double ratio = leaf_radius_m > 0.0 ? leaf_height_m / leaf_radius_m : 0.0;
  // Each blob's contour on its own plane: the rim of a bowl whose height
  // grows with its size (features.h); weeds are low, placed alike.
  o.features.plane_height_m = leaf_height_m;
  o.features.crop_height_per_radius = ratio;
  o.features.weed_height_per_radius = ratio;
  o.tracker.method = MotionMethod::kOurs;
  o.tracker.fit_row_heading = false;  // the prior's rotation comes from the caller
  o.tracker.min_matches = 2;
  UsePriorSearch(o.tracker, o.features);
  return o;
}

void UsePriorSearch(TrackerOptions& tracker, FeatureOptions& features) {
  tracker.prior_gate_m = 0.006;
  tracker.residual_gate_m = 0.005;
  tracker.min_matched_fraction = 0.05;
  features.min_sharpness_rad = 0.9;
}

VisualOdometry::VisualOdometry(const geometry::CameraModel& camera,
                               const VisualOdometryOptions& options)
    : options_(options), camera_(camera), extractor_(options.features),
      tracker_(options.tracker, camera_, options.features.plane_height_m) {
  ThrowIfInvalid("VisualOdometryOptions", options.Validate());
}

void VisualOdometry::Invalid(const std::string& why) {
  last_.valid = false;
  last_.reason = why;
}

const VisualMotion& VisualOdometry::Update(int64_t utime, std::span<const vision::Blob> blobs,
                                           double prior_speed_m_s, double prior_yaw_rate_rad_s,
                                           double camera_pitch_rad) {
  const std::vector<Feature>& features =
      camera_pitch_rad == 0.0 ? extractor_.Extract(blobs, camera_)
                              : extractor_.Extract(blobs, WithPitch(camera_, camera_pitch_rad));
  return UpdateFeatures(utime, features, prior_speed_m_s, prior_yaw_rate_rad_s);
}

const VisualMotion& VisualOdometry::UpdateFeatures(int64_t utime, std::span<const Feature> features,
                                                   double prior_speed_m_s,
                                                   double prior_yaw_rate_rad_s) {
  last_ = VisualMotion{};
  last_.utime = utime;
  last_.features = static_cast<int>(features.size());
  const double dt = previous_utime_ < 0 ? 0.0 : 1e-6 * static_cast<double>(utime - previous_utime_);
  previous_utime_ = utime;
  last_.dt_s = dt;
  if (dt > 0.0 && dt <= options_.max_frame_gap_s) {
    // The scene's motion is opposite to the vehicle's (planar_motion.h).
    const PlanarMotion prior{-prior_yaw_rate_rad_s * dt, {0.0, -prior_speed_m_s * dt}};
    tracker_.SetMotionPrior(prior, options_.prior_psi_sd_rad);
  }
  const FrameMotion& m = tracker_.Update(features);
  last_.matches = m.matched;
  last_.residual_rms_m = m.residual_rms_m;
  if (dt <= 0.0 || dt > options_.max_frame_gap_s) {
    Invalid(dt <= 0.0 ? "no previous frame" : "frames too far apart to pair");
  } else if (!m.locked) {
    Invalid(Name(m.loss));
  } else if (m.matched < options_.min_matches) {
    Invalid("too few matches (" + std::to_string(m.matched) + ")");
  } else if (m.residual_rms_m > options_.max_residual_rms_m) {
    Invalid("matches do not fit one motion");
  } else {
    last_.valid = true;
    last_.speed_m_s = -m.motion.t_m.y() / dt;
    last_.yaw_rate_rad_s = -m.motion.psi_rad / dt;
    // The fit's own precision: translation σ²/N, rotation through the
    // prior's weight (never below the prior's).
    const double sigma = std::max(m.residual_rms_m, options_.tracker.measurement_sigma_m);
    const double n = static_cast<double>(m.matched);
    last_.speed_sd_m_s = std::max(options_.min_speed_sd_m_s, sigma / std::sqrt(n) / dt);
    last_.yaw_rate_sd_rad_s =
        std::max(options_.min_yaw_rate_sd_rad_s, options_.prior_psi_sd_rad / dt);
  }
  return last_;
}

}  // namespace plantscale::motion
