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

#include <array>
#include <cmath>
#include <cstdint>
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
  // The camera's distance scale, learnt against the wheels' (× the
  // tracker's odometry scale) while the two agree: the distance over which
  // old agreement is forgotten, the distance needed before the scale is
  // applied, and the bounds it is held within.
  double scale_memory_m = 20.0;
  double scale_min_distance_m = 3.0;
  double scale_bound = 0.2;
  // Wheels that agree with the camera within the gate on every frame but
  // disagree by the same amount frame after frame (a scale error, a slow
  // spin): the camera's estimates are independent from frame to frame, so
  // the mean of their differences from the wheels over the last
  // `persistence_frames` frames has σ/√n, and beyond `persistence_z` of
  // that the wheels are taken to be at fault (PersistentDisagreement).
  int persistence_frames = 12;
  double persistence_z = 4.0;
  // The camera's features placed with its pitch from frame to frame, read
  // off the soil's texture (motion::GroundShiftOptions::Soil(), the near
  // and far halves' along shifts): the camera's bounce moves them by about
  // 12 mm a frame on `field`, twice the search's gate around the prior.
  // On `field` (session 34, tuning seeds 1–4) placement over a 30 % wheel
  // spin 10.6 → 9.9 mm and over stopped odometry 14.2 → 11.5 mm (means),
  // with no fault 9.75 → 9.9 mm; about 7.5 ms a frame at 640×480 (the
  // soil's view and six correlations, BM_PipelineFrame camera:1 against
  // camera:2). Where the soil gives no shift the pitch returns to level.
  bool camera_pitch = true;

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

// The camera's speeds × scale (σ alike); the yaw rate is an angle, kept.
PlanarSpeed Scaled(const PlanarSpeed& s, double scale);

// The ratio of the wheels' distance to the camera's while they agree. The
// camera's speed is a pixel motion turned into metres through the height of
// the contour features above the ground, taken from the crop profile: a
// profile a few centimetres off the crop scales every camera speed alike,
// a bias that no per-frame σ covers and that, standing in for silent wheels
// over metres, puts the spray centimetres along the row. The wheels × the
// tracker's odometry scale (learnt on the plants) measure it while both
// sources are sound.
class VisualScale {
 public:
  explicit VisualScale(const MotionFusionOptions& options) : options_(options) {}
  // An agreeing pair of speeds held for dt_s.
  void Add(double wheel_speed_m_s, double camera_speed_m_s, double dt_s);
  // 1 until the camera has covered scale_min_distance_m in agreement.
  double ratio() const;
  bool learnt() const;  // the ratio is applied (not the 1 of too little agreement)

 private:
  MotionFusionOptions options_;
  double wheel_m_ = 0.0, camera_m_ = 0.0;  // forgetting sums of |distance|
};

// The wheels' forward speed against the camera's, one camera estimate at a
// time, over a window of the last frames. A per-sample gate of 99.9 %
// passes a 20 % scale error at 0.7 m/s (0.14 m/s against a summed σ of
// 0.04 m/s) whenever the camera reads a little short of the truth, and the
// two are then fused: the tracker dead-reckons on wheels still mostly
// wrong, learns their scale from the plants, and the grid slides along
// the row by centimetres while its σ says millimetres. Over a window the
// same error stands many σ out. Only once the camera's scale is learnt
// (VisualScale): before that a camera a few per cent off would condemn
// sound wheels.
class PersistentDisagreement {
 public:
  static constexpr int kMaxFrames = 32;
  explicit PersistentDisagreement(const MotionFusionOptions& options) : options_(options) {}
  // The camera's estimate of `camera_utime` against the wheels at its use;
  // a second call for the same estimate is ignored.
  void Add(int64_t camera_utime, const PlanarSpeed& wheels, const PlanarSpeed& camera);
  // The window's mean difference in units of its σ (0 until it is full).
  double z() const;
  // The wheels less the window's mean difference, its σ added: the wheels'
  // frame-to-frame smoothness at the camera's scale, to be weighed with
  // the camera's own estimate.
  PlanarSpeed Corrected(const PlanarSpeed& wheels) const;
  bool wheels_off() const { return std::abs(z()) > options_.persistence_z; }

 private:
  MotionFusionOptions options_;
  int64_t last_utime_ = -1;
  int count_ = 0, next_ = 0;
  std::array<double, kMaxFrames> difference_{}, variance_{};
};

// Back to wheel speeds (divided by the scale, as the tracker's input).
void ToWheels(const PlanarSpeed& s, double scale, double track_width_m, double& left_m_s,
              double& right_m_s);

// The σ of each wheel's speed, as a fraction of the mean wheel speed, that
// gives the speed's and the yaw rate's σ of `s` together (the tracker's
// dead reckoning takes one σ per wheel): √(σ_v² + (σ_ω·W/2)²) / |v|, the
// speed floored at 0.1 m/s.
double WheelSdFraction(const PlanarSpeed& s, double track_width_m);

}  // namespace plantscale::pipeline
