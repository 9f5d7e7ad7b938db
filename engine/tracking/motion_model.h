#pragma once
// Differential-drive prediction of the crop-grid state (thesis eq. 4.3),
// written exactly rather than with the small-angle form: the vehicle drives
// the mean of its wheel increments along its heading and turns by their
// difference over the track width. The grid does not move, so the state
// (t_x, Y, Ψ) is recomputed from where the grid's origin plant and row
// direction land in the new vehicle frame; r̄ and l̄ are unchanged.

#include <Eigen/Core>

#include "engine/geometry/grid_model.h"

namespace plantscale::tracking {

struct WheelIncrement {
  double left_m = 0.0;   // u_1
  double right_m = 0.0;  // u_2
};

struct MotionPrediction {
  geometry::GridState state;
  geometry::Matrix5d d_state;                  // ∂f/∂(t_x, Y, Ψ, r̄, l̄)
  Eigen::Matrix<double, 5, 2> d_wheels;        // ∂f/∂(u_1, u_2)
};

// f(x, u) of eq. 4.3 for a track width W (metres between the driven wheels).
MotionPrediction PredictGridMotion(const geometry::GridState& state, const WheelIncrement& u,
                                   double track_width_m);

}  // namespace plantscale::tracking
