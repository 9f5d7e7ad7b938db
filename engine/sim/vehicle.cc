#include "engine/sim/vehicle.h"

#include <cmath>
#include <numbers>

namespace plantscale::sim {

Eigen::Vector2d FieldToVehicle(const Pose2& pose, const Eigen::Vector2d& field_m) {
  const double c = std::cos(pose.heading_rad);
  const double s = std::sin(pose.heading_rad);
  const double dx = field_m.x() - pose.x_m;
  const double dy = field_m.y() - pose.y_m;
  return {c * dx + s * dy, -s * dx + c * dy};
}

OptionErrors VehicleOptions::Validate() const {
  OptionErrors e;
  RequireInRange(e, "speed_m_s", speed_m_s, 0.0, 5.0, false, true);
  RequirePositive(e, "track_width_m", track_width_m);
  RequireFinite(e, "start_offset_m", start_offset_m);
  RequireInRange(e, "start_heading_rad", start_heading_rad, -0.5, 0.5);
  RequireNonNegative(e, "zigzag_amplitude_m", zigzag_amplitude_m);
  RequirePositive(e, "zigzag_wavelength_m", zigzag_wavelength_m);
  RequireNonNegative(e, "heading_wander_sd_rad", heading_wander_sd_rad);
  RequireInRange(e, "odometry_rate_hz", odometry_rate_hz, 1.0, 1000.0);
  RequireInRange(e, "odometry_noise_fraction", odometry_noise_fraction, 0.0, 0.5);
  RequireInRange(e, "odometry_scale_error", odometry_scale_error, -0.5, 0.5);
  RequireInRange(e, "wheel_scale_difference", wheel_scale_difference, -0.2, 0.2);
  RequireNonNegative(e, "slip_bursts_per_100m", slip_bursts_per_100m);
  RequireNonNegative(e, "slip_burst_length_m", slip_burst_length_m);
  RequireInRange(e, "slip_fraction", slip_fraction, 0.0, 1.0);
  RequireNonNegative(e, "bump_pitch_sd_rad", bump_pitch_sd_rad);
  RequireNonNegative(e, "bump_roll_sd_rad", bump_roll_sd_rad);
  RequireNonNegative(e, "bump_height_sd_m", bump_height_sd_m);
  RequirePositive(e, "bump_correlation_s", bump_correlation_s);
  RequireInRange(e, "frame_rate_hz", frame_rate_hz, 0.1, 200.0);
  RequireNonNegative(e, "frame_jitter_s", frame_jitter_s);
  RequireInRange(e, "dropped_frame_fraction", dropped_frame_fraction, 0.0, 0.9);
  RequireInRange(e, "exposure_s", exposure_s, 0.0, 0.1);
  if (std::isfinite(frame_rate_hz) && std::isfinite(odometry_rate_hz) &&
      odometry_rate_hz < frame_rate_hz) {
    e.push_back({"odometry_rate_hz", "must be at least frame_rate_hz"});
  }
  return e;
}

Vehicle::Vehicle(const VehicleOptions& options, uint64_t seed)
    : options_(options), rng_(Rng::Derived(seed, 0x7e41c1e)) {
  ThrowIfInvalid("vehicle", options.Validate());
  pose_.x_m = options.start_offset_m;
  pose_.heading_rad = options.start_heading_rad;
}

double Vehicle::TargetHeading() const {
  // Steer along x_ref(y) = x0 + A·sin(2πy/λ): heading = −atan(dx_ref/dy)
  // (CCW heading points to −x), plus a pull back onto x_ref.
  const VehicleOptions& o = options_;
  const double k = 2.0 * std::numbers::pi / o.zigzag_wavelength_m;
  const double x_ref = o.start_offset_m + o.zigzag_amplitude_m * std::sin(k * pose_.y_m);
  const double slope = o.zigzag_amplitude_m * k * std::cos(k * pose_.y_m);
  const double pull = 0.5 * (pose_.x_m - x_ref);  // rad per metre of lateral error
  return -std::atan(slope) + std::clamp(pull, -0.05, 0.05);
}

OdometrySample Vehicle::Step() {
  const VehicleOptions& o = options_;
  const double dt = 1.0 / o.odometry_rate_hz;
  // AR(1) processes: heading wander and camera bounce.
  const double a_bump = std::exp(-dt / o.bump_correlation_s);
  const double b_bump = std::sqrt(1.0 - a_bump * a_bump);
  bounce_.pitch_rad = a_bump * bounce_.pitch_rad + b_bump * rng_.Normal(0.0, o.bump_pitch_sd_rad);
  bounce_.roll_rad = a_bump * bounce_.roll_rad + b_bump * rng_.Normal(0.0, o.bump_roll_sd_rad);
  bounce_.height_m = a_bump * bounce_.height_m + b_bump * rng_.Normal(0.0, o.bump_height_sd_m);
  const double a_wander = std::exp(-dt / 2.0);
  wander_ = a_wander * wander_ +
            std::sqrt(1.0 - a_wander * a_wander) * rng_.Normal(0.0, o.heading_wander_sd_rad);

  // True motion over dt (eq. 4.3): forward ds, turn dψ; wheel ground speeds.
  const double ds = o.speed_m_s * dt;
  const double target = TargetHeading() + wander_;
  const double dpsi = std::clamp(target - pose_.heading_rad, -0.3 * ds, 0.3 * ds);
  const double mid_heading = pose_.heading_rad + 0.5 * dpsi;
  pose_.x_m -= ds * std::sin(mid_heading);
  pose_.y_m += ds * std::cos(mid_heading);
  pose_.heading_rad += dpsi;
  distance_ += ds;
  utime_ += static_cast<int64_t>(std::llround(dt * 1e6));

  OdometrySample s;
  s.utime = utime_;
  s.true_left_m_s = (ds - 0.5 * o.track_width_m * dpsi) / dt;
  s.true_right_m_s = (ds + 0.5 * o.track_width_m * dpsi) / dt;
  // Slip bursts: Poisson in distance; the wheels spin faster than the ground moves.
  if (slip_left_m_ <= 0.0 && rng_.Bernoulli(o.slip_bursts_per_100m * ds / 100.0)) {
    slip_left_m_ = o.slip_burst_length_m;
  }
  s.slipping = slip_left_m_ > 0.0;
  slip_left_m_ -= ds;
  const double slip = s.slipping ? 1.0 + o.slip_fraction : 1.0;
  const double noise = o.odometry_noise_fraction * o.speed_m_s;
  s.left_m_s =
      s.true_left_m_s * slip * (1.0 + o.odometry_scale_error - 0.5 * o.wheel_scale_difference) +
      rng_.Normal(0.0, noise);
  s.right_m_s =
      s.true_right_m_s * slip * (1.0 + o.odometry_scale_error + 0.5 * o.wheel_scale_difference) +
      rng_.Normal(0.0, noise);
  return s;
}

}  // namespace plantscale::sim
