#include "engine/tracking/process_model.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "engine/common/check.h"

namespace plantscale::tracking {

using geometry::GridState;

Transition TransitionFrom(const StateLayout& layout, const TrackerOptions& options,
                          const GridState& s, double scale, const WheelIncrement& measured,
                          double left_sd_m, double right_sd_m, double dt_s) {
  // Eq. 4.3 driven by the wheel increments corrected by the scale state:
  // u = (1 + k)·u_measured, so ∂f/∂k = ∂f/∂u · u_measured.
  const int c = layout.core();
  const int h = layout.head();
  const double distance = std::abs(0.5 * (measured.left_m + measured.right_m));
  const WheelIncrement u{scale * measured.left_m, scale * measured.right_m};
  Transition t{PredictGridMotion(s, u, options.track_width_m), Eigen::MatrixXd::Identity(h, h),
               Eigen::MatrixXd::Zero(h, h), 1.0};
  t.a.topLeftCorner(c, c) = t.f.d_state.topLeftCorner(c, c);
  const Eigen::MatrixXd g = t.f.d_wheels.topRows(c);
  if (options.estimate_odometry_scale) {
    t.a.block(0, c, c, 1) = g * Eigen::Vector2d(measured.left_m, measured.right_m);
  }
  t.q.topLeftCorner(c, c) = g * Eigen::Vector2d(left_sd_m * left_sd_m, right_sd_m * right_sd_m)
                                    .asDiagonal() * g.transpose() * (scale * scale);
  t.q(GridState::kOffset, GridState::kOffset) +=
      options.lateral_sd_per_sqrt_m * options.lateral_sd_per_sqrt_m * distance;
  t.q(GridState::kForward, GridState::kForward) +=
      options.forward_sd_per_sqrt_m * options.forward_sd_per_sqrt_m * distance;
  t.q(GridState::kBearing, GridState::kBearing) +=
      options.bearing_sd_per_sqrt_m * options.bearing_sd_per_sqrt_m * distance;
  if (options.estimate_odometry_scale) {
    t.q(c, c) = options.odometry_scale_step_sd_per_sqrt_m *
                options.odometry_scale_step_sd_per_sqrt_m * distance;
  }
  if (layout.persistent_bounce()) {
    // First-order Gauss–Markov: b ← a·b, stationary variance kept.
    const int b = layout.bounce_index();
    t.bounce_decay = std::exp(-std::max(0.0, dt_s) / options.camera_bounce_correlation_s);
    t.a.block<3, 3>(b, b) = t.bounce_decay * Eigen::Matrix3d::Identity();
    t.q.block<3, 3>(b, b) = (1.0 - t.bounce_decay * t.bounce_decay) * BouncePrior(options).asDiagonal();
  }
  return t;
}

GridAhead PredictGridAhead(const StateLayout& layout, const TrackerOptions& options,
                           const GridState& s, const Eigen::MatrixXd& p_head,
                           const WheelMotion& wheels, double distance_m, double step_m) {
  PLANTSCALE_CHECK(distance_m >= 0.0 && step_m > 0.0, "a distance ahead and a positive step");
  const int c = layout.core();
  GridAhead ahead;
  ahead.state = s;
  Eigen::MatrixXd p = p_head;
  // The wheels' current ratio (straight ahead when stopped), driven forward.
  const double speed = 0.5 * (wheels.left_m_s + wheels.right_m_s);
  const bool moving = wheels.have_speeds && speed > 1e-6;
  const double left_share = moving ? wheels.left_m_s / speed : 1.0;
  const double right_share = moving ? wheels.right_m_s / speed : 1.0;
  const int steps = static_cast<int>(std::ceil(distance_m / step_m - 1e-9));
  const double scale = wheels.scale;
  for (int i = 0; i < steps; ++i) {
    const double d = std::min(step_m, distance_m - i * step_m) / scale;  // measured
    const WheelIncrement u{left_share * d, right_share * d};
    const double dt = moving ? d / speed : 0.0;
    const Transition t = TransitionFrom(layout, options, ahead.state, scale, u,
                                        options.wheel_sd_fraction * std::abs(u.left_m),
                                        options.wheel_sd_fraction * std::abs(u.right_m), dt);
    ahead.state.offset_m = t.f.state.offset_m;
    ahead.state.forward_m = t.f.state.forward_m;
    ahead.state.bearing_rad = t.f.state.bearing_rad;
    p = t.a * p * t.a.transpose() + t.q;
  }
  ahead.covariance.topLeftCorner(c, c) = p.topLeftCorner(c, c);
  if (layout.calibration()) {
    // Given the calibration: its error is a fixed bias of every frame, not
    // an uncertainty that grows while coasting (the footprint's size covers it).
    const int k = layout.calibration_index();
    const Eigen::MatrixXd pck = p.block(0, k, c, 4);
    ahead.covariance.topLeftCorner(c, c) -= pck * p.block<4, 4>(k, k).ldlt().solve(pck.transpose());
  }
  return ahead;
}

}  // namespace plantscale::tracking
