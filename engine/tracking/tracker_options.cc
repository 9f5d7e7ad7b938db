#include "engine/tracking/tracker_options.h"

namespace plantscale::tracking {

OptionErrors TrackerOptions::Validate() const {
  OptionErrors e;
  if (rows_each_side < 0 || rows_each_side > 10) e.push_back({"rows_each_side", "must be in [0, 10]"});
  RequirePositive(e, "row_spacing_m", row_spacing_m);
  RequirePositive(e, "plant_spacing_m", plant_spacing_m);
  RequireNonNegative(e, "row_spacing_sd_m", row_spacing_sd_m);
  RequireNonNegative(e, "plant_spacing_sd_m", plant_spacing_sd_m);
  RequireNonNegative(e, "spacing_step_sd_m", spacing_step_sd_m);
  RequireNonNegative(e, "spacing_check_chi2", spacing_check_chi2);
  RequireInRange(e, "spacing_check_scale_sd", spacing_check_scale_sd, 0.0, 0.5);
  RequirePositive(e, "plant_offset_sd_m", plant_offset_sd_m);
  RequireNonNegative(e, "plant_offset_walk_across_sd_per_sqrt_m", plant_offset_walk_across_sd_per_sqrt_m);
  RequireNonNegative(e, "plant_offset_walk_along_sd_per_sqrt_m", plant_offset_walk_along_sd_per_sqrt_m);
  RequirePositive(e, "plant_height_sd_m", plant_height_sd_m);
  RequirePositive(e, "size_height_sd_m", size_height_sd_m);
  RequireInRange(e, "size_ratio_max", size_ratio_max, 1.0, 10.0, false, true);
  RequireInRange(e, "size_edge_loss_m", size_edge_loss_m, 0.0, 1.0);
  if (size_bands < 1 || size_bands > 480) e.push_back({"size_bands", "must be in [1, 480]"});
  if (size_min_samples < 1) e.push_back({"size_min_samples", "must be >= 1"});
  RequireInRange(e, "size_mean_weight", size_mean_weight, 0.0, 1.0, false, true);
  RequirePositive(e, "feature_sd_m", feature_sd_m);
  RequireNonNegative(e, "crop_radius_m", crop_radius_m);
  RequireNonNegative(e, "crop_height_m", crop_height_m);
  if ((crop_radius_m > 0.0) != (crop_height_m > 0.0)) {
    e.push_back({"crop_height_m", "crop_radius_m and crop_height_m are set together (or both 0)"});
  }
  RequireNonNegative(e, "pixel_sd_px", pixel_sd_px);
  RequireNonNegative(e, "camera_pitch_sd_rad", camera_pitch_sd_rad);
  RequireNonNegative(e, "camera_roll_sd_rad", camera_roll_sd_rad);
  RequireNonNegative(e, "camera_height_sd_m", camera_height_sd_m);
  RequireNonNegative(e, "camera_bounce_correlation_s", camera_bounce_correlation_s);
  RequireInRange(e, "calibration_pitch_sd_rad", calibration_pitch_sd_rad, 0.0, 0.2);
  RequireInRange(e, "calibration_roll_sd_rad", calibration_roll_sd_rad, 0.0, 0.2);
  RequireInRange(e, "calibration_height_sd_m", calibration_height_sd_m, 0.0, 0.2);
  RequireInRange(e, "calibration_focal_sd", calibration_focal_sd, 0.0, 0.2);
  RequirePositive(e, "track_width_m", track_width_m);
  RequireNonNegative(e, "wheel_sd_fraction", wheel_sd_fraction);
  RequireNonNegative(e, "forward_sd_per_sqrt_m", forward_sd_per_sqrt_m);
  RequireNonNegative(e, "lateral_sd_per_sqrt_m", lateral_sd_per_sqrt_m);
  RequireNonNegative(e, "bearing_sd_per_sqrt_m", bearing_sd_per_sqrt_m);
  RequirePositive(e, "odometry_scale_sd", odometry_scale_sd);
  RequireNonNegative(e, "odometry_scale_step_sd_per_sqrt_m", odometry_scale_step_sd_per_sqrt_m);
  RequireNonNegative(e, "frame_offset_sd_m", frame_offset_sd_m);
  RequireNonNegative(e, "frame_forward_sd_m", frame_forward_sd_m);
  RequireNonNegative(e, "frame_bearing_sd_rad", frame_bearing_sd_rad);
  RequirePositive(e, "gate_chi2", gate_chi2);
  RequirePositive(e, "strip_gate_chi2", strip_gate_chi2);
  RequireNonNegative(e, "strip_sd_m", strip_sd_m);
  RequireInRange(e, "strip_max_offset_fraction", strip_max_offset_fraction, 0.0, 0.5);
  RequireNonNegative(e, "edge_margin_px", edge_margin_px);
  RequireInRange(e, "min_feature_area_fraction", min_feature_area_fraction, 0.0, 1.0);
  RequirePositive(e, "max_wheel_speed_m_s", max_wheel_speed_m_s);
  RequirePositive(e, "max_odometry_gap_s", max_odometry_gap_s);
  RequirePositive(e, "max_frame_lag_s", max_frame_lag_s);
  RequirePositive(e, "lost_offset_sd_m", lost_offset_sd_m);
  RequirePositive(e, "max_coast_s", max_coast_s);
  for (auto& error : init.Validate()) e.push_back({"init." + error.key, error.reason});
  for (auto& error : slip_guard.Validate()) e.push_back({"slip_guard." + error.key, error.reason});
  return e;
}

}  // namespace plantscale::tracking
