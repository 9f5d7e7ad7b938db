#include "engine/tracking/inputs.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>

#include "engine/tracking/grid_tracker_internal.h"

namespace plantscale::tracking {

namespace {

bool Finite(const Feature& f) {
  return std::isfinite(f.ground_m.x()) && std::isfinite(f.ground_m.y()) &&
         std::isfinite(f.image_px.x()) && std::isfinite(f.image_px.y()) &&
         std::isfinite(f.area_m2);
}

}  // namespace

DeadReckoning::DeadReckoning(const TrackerOptions& options)
    : max_wheel_speed_m_s_(options.max_wheel_speed_m_s),
      max_odometry_gap_s_(options.max_odometry_gap_s),
      wheel_sd_fraction_(options.wheel_sd_fraction),
      slip_guard_(options.slip_guard) {}

OdometryIntake DeadReckoning::Accept(int64_t utime, int64_t state_utime, double left_m_s,
                                     double right_m_s, double sd_fraction) {
  if (utime > last_wheels_utime_) last_wheels_utime_ = utime;
  OdometryIntake out;
  std::string problem;
  if (!std::isfinite(left_m_s) || !std::isfinite(right_m_s)) {
    problem = "wheel speed is not a number";
  } else if (std::abs(left_m_s) > max_wheel_speed_m_s_ || std::abs(right_m_s) > max_wheel_speed_m_s_) {
    std::ostringstream text;
    text << "wheel speed (" << left_m_s << ", " << right_m_s << ") m/s beyond "
         << max_wheel_speed_m_s_ << " m/s";
    problem = text.str();
  }
  if (state_utime < 0) {
    out.advance = true;
    if (problem.empty()) {
      const WheelSpeeds w = slip_guard_.Filter({left_m_s, right_m_s}, 0.0);
      left_m_s_ = w.left_m_s;
      right_m_s_ = w.right_m_s;
      have_speeds_ = true;
    } else {
      out.status = {false, "odometry refused: " + problem};
    }
    return out;
  }
  if (utime <= state_utime) {
    out.status = {false, "odometry refused: time " + std::to_string(utime) +
                             " us is not after the state's " + std::to_string(state_utime) + " us"};
    return out;
  }
  out.advance = true;
  const double dt = (utime - state_utime) * 1e-6;
  if (dt > max_odometry_gap_s_ && problem.empty()) {
    problem = "gap of " + Seconds(dt) + " in odometry";
  }
  if (!problem.empty()) {
    // Bridge the period with the last speeds we trust and a wheel
    // uncertainty of half of a brisk walking pace: the pose stays usable,
    // its covariance says how much less.
    const double sd = BridgeSd(dt);
    out.step = WheelStep{Over(dt), sd, sd, dt};
    if (std::isfinite(left_m_s) && std::isfinite(right_m_s) &&
        std::abs(left_m_s) <= max_wheel_speed_m_s_ && std::abs(right_m_s) <= max_wheel_speed_m_s_) {
      left_m_s_ = left_m_s;
      right_m_s_ = right_m_s;
      have_speeds_ = true;
    }
    out.status = {false, "odometry refused: " + problem + "; bridged by dead reckoning"};
    return out;
  }
  const WheelSpeeds w = slip_guard_.Filter({left_m_s, right_m_s}, dt);
  left_m_s_ = w.left_m_s;
  right_m_s_ = w.right_m_s;
  have_speeds_ = true;
  const WheelIncrement u = Over(dt);
  double left_sd = sd_fraction * std::abs(u.left_m), right_sd = sd_fraction * std::abs(u.right_m);
  if (slip_guard_.faulty_wheel() != 0) {
    // A wheel read from the other (slip_guard.h): the turn rate is the one
    // held when it failed, a guess as the vehicle steers on, so that
    // wheel's increment is given the uncertainty of a fraction of the
    // distance and the rows' bearing takes over.
    const double guess = kWheelFaultSdFraction * std::max(std::abs(u.left_m), std::abs(u.right_m));
    double& sd = slip_guard_.faulty_wheel() == 1 ? left_sd : right_sd;
    sd = std::hypot(sd, guess);
  }
  out.step = WheelStep{u, left_sd, right_sd, dt};
  return out;
}

std::optional<WheelStep> DeadReckoning::StepTo(int64_t utime, int64_t state_utime) const {
  if (!have_speeds_) return std::nullopt;
  const double dt = (utime - state_utime) * 1e-6;
  const WheelIncrement u = Over(dt);
  if (WheelsSilentAt(utime)) {
    // No odometry for longer than a gap: the speeds are the last ones
    // heard, a guess as the vehicle drives and steers on, with the
    // uncertainty of the odometry-gap bridge (Accept), so the rows and
    // plants take over the bearing and the distance.
    const double sd = BridgeSd(dt);
    return WheelStep{u, sd, sd, dt};
  }
  return WheelStep{u, wheel_sd_fraction_ * std::abs(u.left_m), wheel_sd_fraction_ * std::abs(u.right_m),
                   dt};
}

bool DeadReckoning::WheelsSilentAt(int64_t utime) const {
  return last_wheels_utime_ >= 0 && (utime - last_wheels_utime_) * 1e-6 > max_odometry_gap_s_;
}

// A wheel uncertainty of half of a brisk walking pace over dt.
double DeadReckoning::BridgeSd(double dt) const {
  return 0.5 * std::max({std::abs(left_m_s_), std::abs(right_m_s_), 0.5}) * dt;
}

bool RefuseFrame(const geometry::CameraModel& camera, const TrackerOptions& options,
                 int64_t state_utime, int64_t utime, int width, int height, FrameReport& report) {
  if (width != camera.width() || height != camera.height()) {
    report.input = {false, "frame refused: it is " + std::to_string(width) + "x" +
                               std::to_string(height) + " px, the camera model is " +
                               std::to_string(camera.width()) + "x" +
                               std::to_string(camera.height()) + " px"};
  } else if (state_utime >= 0 && (state_utime - utime) * 1e-6 > options.max_frame_lag_s) {
    report.input = {false, "frame refused: captured " + Seconds((state_utime - utime) * 1e-6) +
                               " before the state's time"};
  } else {
    return false;
  }
  report.skipped_reason = report.input.reason;
  return true;
}

std::vector<Feature> ValidFeatures(std::span<const Feature> features,
                                   const geometry::CentroidHeights* heights, FrameReport& report) {
  std::vector<Feature> valid;
  valid.reserve(features.size());
  int invalid = 0;
  for (const Feature& f : features) {
    if (!Finite(f)) {
      ++invalid;
      continue;
    }
    valid.push_back(f);
    if (heights) {
      const auto located = heights->Locate(f.image_px);
      if (located) valid.back().ground_m = *located;
    }
  }
  if (invalid > 0) {
    report.input.reason = std::to_string(invalid) + " feature(s) with non-finite values ignored";
  }
  return valid;
}

}  // namespace plantscale::tracking
