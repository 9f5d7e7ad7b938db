#pragma once
// The pipeline's two motion sources, weighed: the wheel odometry and the
// vehicle's own camera (motion/visual_odometry.h). Each gives the forward
// ground speed and the yaw rate with a σ; while they agree (χ² of their
// difference under the summed variances within the gate) the speeds the
// tracker dead-reckons with are their precision-weighted mean, and when
// they do not the wheels are taken to be at fault (spinning, a stalled
// encoder, a wrong scale: the camera sees the ground itself) and the
// camera's motion stands in. Without a valid, fresh visual estimate the
// wheels carry on alone.

#include <string>

#include "engine/common/options.h"
#include "engine/motion/visual_odometry.h"

namespace plantscale::pipeline {

struct MotionFusionOptions {
  bool enabled = false;
  motion::VisualOdometryOptions visual;  // motion::VisualOdometryFor(the crop profile)
  double max_visual_age_s = 0.25;   // an estimate older than this weighs nothing
  double gate_chi2 = 13.8;          // 2 dof, 99.9 %
  double wheel_sd_fraction = 0.03;  // σ of a wheel's speed / the speed (the tracker's)
  double min_wheel_sd_m_s = 0.01;
  // Odometry silent this long at a frame: the camera's motion is fed to the
  // tracker as the odometry of the frame's capture.
  double substitute_after_s = 0.1;

  OptionErrors Validate() const;
};

// Forward ground speed and yaw rate (counter-clockwise) with their σ.
struct PlanarSpeed {
  double speed_m_s = 0.0, yaw_rate_rad_s = 0.0;
  double speed_sd_m_s = 0.0, yaw_rate_sd_rad_s = 0.0;
};

// The wheels' (measured speeds × scale, on a track of track_width_m).
PlanarSpeed WheelSpeed(double left_m_s, double right_m_s, double scale, double track_width_m,
                       const MotionFusionOptions& options);
PlanarSpeed VisualSpeed(const motion::VisualMotion& v);

enum class FusedSource { kWheels, kFused, kCamera };
const char* Name(FusedSource source);

struct FusedSpeed {
  PlanarSpeed speed;
  FusedSource source = FusedSource::kWheels;
  double chi2 = 0.0;  // of the two sources' difference (0 with the wheels alone)
};

// `visual` null: the wheels alone.
FusedSpeed Fuse(const PlanarSpeed& wheels, const PlanarSpeed* visual, double gate_chi2);

// Back to wheel speeds (divided by the scale, as the tracker's input).
void ToWheels(const PlanarSpeed& s, double scale, double track_width_m, double& left_m_s,
              double& right_m_s);

// The σ of each wheel's speed, as a fraction of the mean wheel speed, that
// gives the speed's and the yaw rate's σ of `s` together (the tracker's
// dead reckoning takes one σ per wheel): √(σ_v² + (σ_ω·W/2)²) / |v|, the
// speed floored at 0.1 m/s.
double WheelSdFraction(const PlanarSpeed& s, double track_width_m);

}  // namespace plantscale::pipeline
