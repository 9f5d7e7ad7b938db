#pragma once
// The simulated vehicle: a differential-drive platform following the bed
// with a zig-zag steering error (thesis §4.1.1, eq. 4.3), wheel odometry with
// noise, scale error and slip bursts, and a camera that bounces (pitch, roll,
// height). The vehicle is integrated at the odometry rate (50 Hz default).

#include <Eigen/Core>
#include <cstdint>

#include "engine/common/options.h"
#include "engine/common/rng.h"

namespace plantscale::sim {

struct VehicleOptions {
  double speed_m_s = 0.7;
  double track_width_m = 1.5;   // W of eq. 4.3, between the driven wheels
  double start_offset_m = 0.0;  // lateral start position (field x)
  double start_heading_rad = 0.0;
  double zigzag_amplitude_m = 0.03;  // steering error about the row
  double zigzag_wavelength_m = 8.0;
  double heading_wander_sd_rad = 0.003;
  double odometry_rate_hz = 50.0;
  double odometry_noise_fraction = 0.02;  // wheel-speed noise sd / speed, per sample
  double odometry_scale_error = 0.0;      // both wheels read long by this fraction
  double wheel_scale_difference = 0.0;    // right reads long, left short, by half of this
  double slip_bursts_per_100m = 2.0;      // wheel spin: the wheels turn, the ground does not
  double slip_burst_length_m = 0.4;
  double slip_fraction = 0.15;
  double bump_pitch_sd_rad = 0.004;  // camera bounce (the thesis assumes none)
  double bump_roll_sd_rad = 0.003;
  double bump_height_sd_m = 0.004;
  double bump_correlation_s = 0.25;
  double frame_rate_hz = 12.5;
  double frame_jitter_s = 0.002;  // timing jitter of frame capture
  double dropped_frame_fraction = 0.0;
  double exposure_s = 0.002;  // motion blur = speed · exposure

  OptionErrors Validate() const;
};

struct Pose2 {
  double x_m = 0.0;
  double y_m = 0.0;
  double heading_rad = 0.0;  // of the forward axis from the field y axis, CCW
};

// Vehicle-frame position of a field-frame point seen from `pose` (thesis
// eq. A.1 in 2-D; docs/design.md §3: vehicle y forward, x right).
Eigen::Vector2d FieldToVehicle(const Pose2& pose, const Eigen::Vector2d& field_m);

struct OdometrySample {
  int64_t utime = 0;
  double left_m_s = 0.0;  // measured wheel speeds, what the vehicle reports
  double right_m_s = 0.0;
  double true_left_m_s = 0.0;  // ground speed under each wheel
  double true_right_m_s = 0.0;
  bool slipping = false;
};

struct CameraBounce {
  double pitch_rad = 0.0;  // added to the tilt
  double roll_rad = 0.0;
  double height_m = 0.0;  // added to the height
};

class Vehicle {
 public:
  Vehicle(const VehicleOptions& options, uint64_t seed);

  // Advances one odometry period and returns the sample for it.
  OdometrySample Step();
  const Pose2& pose() const { return pose_; }
  const CameraBounce& bounce() const { return bounce_; }
  int64_t utime() const { return utime_; }
  double distance_m() const { return distance_; }
  const VehicleOptions& options() const { return options_; }

 private:
  double TargetHeading() const;

  VehicleOptions options_;
  Rng rng_;
  Pose2 pose_;
  CameraBounce bounce_;
  int64_t utime_ = 0;
  double distance_ = 0.0;
  double wander_ = 0.0;
  double slip_left_m_ = 0.0;  // remaining length of the current slip burst
};

}  // namespace plantscale::sim
