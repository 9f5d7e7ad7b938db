#pragma once
// The grid tracker's process model (thesis eq. 4.3 and its noise): one
// dead-reckoning step of the head of the state (the grid, the wheels' scale
// k, a persistent bounce) as its mean, its transition A and its process
// noise Q; and the grid predicted ahead by dead reckoning alone. The
// motion itself (the exact differential drive and its Jacobians) is
// motion_model.h; the filter that applies A and Q is kalman_filter.h.

#include <Eigen/Core>

#include "engine/geometry/grid_model.h"
#include "engine/tracking/motion_model.h"
#include "engine/tracking/state_layout.h"
#include "engine/tracking/tracker_report.h"

namespace plantscale::tracking {

struct Transition {
  MotionPrediction f;    // the motion of the grid's mean
  Eigen::MatrixXd a, q;  // head() × head()
  double bounce_decay = 1.0;
};

// One step from `s` driven by the measured wheel increments `measured`,
// scaled by the wheels' scale (1 + k) and each of σ left_sd_m, right_sd_m;
// dt_s decays a persistent bounce.
Transition TransitionFrom(const StateLayout& layout, const TrackerOptions& options,
                          const geometry::GridState& s, double scale, const WheelIncrement& measured,
                          double left_sd_m, double right_sd_m, double dt_s);

// The wheels' speeds and scale the tracker dead-reckons with.
struct WheelMotion {
  double left_m_s = 0.0;
  double right_m_s = 0.0;
  bool have_speeds = false;
  double scale = 1.0;  // 1 + k
};

// GridTracker::PredictAhead: `p_head` is the head block of the filter's
// covariance at `s`.
GridAhead PredictGridAhead(const StateLayout& layout, const TrackerOptions& options,
                           const geometry::GridState& s, const Eigen::MatrixXd& p_head,
                           const WheelMotion& wheels, double distance_m, double step_m);

}  // namespace plantscale::tracking
