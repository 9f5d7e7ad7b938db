#pragma once
// What the grid tracker takes in, and what it refuses: wheel odometry,
// turned into dead-reckoning steps with their σ past the slip guard and
// across gaps (DeadReckoning), and camera frames and their features
// (RefuseFrame, ValidFeatures). The steps drive the filter's prediction
// (process_model.h, kalman_filter.h).

#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "engine/geometry/camera_model.h"
#include "engine/geometry/centroid_height.h"
#include "engine/tracking/feature.h"
#include "engine/tracking/motion_model.h"
#include "engine/tracking/slip_guard.h"
#include "engine/tracking/tracker_options.h"
#include "engine/tracking/tracker_report.h"

namespace plantscale::tracking {

// A dead-reckoning step: the measured wheel increments over dt_s and each
// one's σ.
struct WheelStep {
  WheelIncrement u;
  double left_sd_m = 0.0;
  double right_sd_m = 0.0;
  double dt_s = 0.0;
};

// An odometry sample's outcome: accepted or refused, whether the state's
// time moves to the sample's, and the step to predict over, if any.
struct OdometryIntake {
  InputStatus status;
  bool advance = false;
  std::optional<WheelStep> step;
};

class DeadReckoning {
 public:
  explicit DeadReckoning(const TrackerOptions& options);

  // GridTracker::AddOdometry with the state's time `state_utime` (−1
  // before any): a refused speed or a gap over max_odometry_gap_s is
  // bridged with the last speeds trusted and a wheel σ of half a brisk
  // walking pace; otherwise the slip guard's speeds, each increment's σ
  // sd_fraction of it (a wheel read from the other: its share of
  // kWheelFaultSdFraction added).
  OdometryIntake Accept(int64_t utime, int64_t state_utime, double left_m_s, double right_m_s,
                        double sd_fraction);
  // The step from state_utime to a later utime at the last speeds (none
  // before any speed); with no odometry for over a gap, bridged as above.
  std::optional<WheelStep> StepTo(int64_t utime, int64_t state_utime) const;
  // The wheels' increments over dt_s at the last speeds.
  WheelIncrement Over(double dt_s) const { return {left_m_s_ * dt_s, right_m_s_ * dt_s}; }
  void Reset() { slip_guard_.Reset(); }

  double left_m_s() const { return left_m_s_; }
  double right_m_s() const { return right_m_s_; }
  bool have_speeds() const { return have_speeds_; }
  const SlipGuard& slip_guard() const { return slip_guard_; }

 private:
  // No odometry sample for longer than max_odometry_gap_s before utime.
  bool WheelsSilentAt(int64_t utime) const;
  // The odometry-gap bridge's σ of each wheel's increment over dt.
  double BridgeSd(double dt) const;

  double max_wheel_speed_m_s_;
  double max_odometry_gap_s_;
  double wheel_sd_fraction_;
  int64_t last_wheels_utime_ = -1;  // newest odometry sample offered, accepted or not
  SlipGuard slip_guard_;
  double left_m_s_ = 0.0;  // last accepted wheel speeds (past the slip guard)
  double right_m_s_ = 0.0;
  bool have_speeds_ = false;
};

// The frame's refusal (a size not the camera model's, or captured longer
// before the state's time than max_frame_lag_s), noted in the report.
bool RefuseFrame(const geometry::CameraModel& camera, const TrackerOptions& options,
                 int64_t state_utime, int64_t utime, int width, int height, FrameReport& report);

// The features with finite values, located on `heights` when given; the
// number ignored goes into the report.
std::vector<Feature> ValidFeatures(std::span<const Feature> features,
                                   const geometry::CentroidHeights* heights, FrameReport& report);

}  // namespace plantscale::tracking
