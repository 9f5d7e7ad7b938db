#pragma once
// Fail-safe on uncertainty: where the plants will stand when the spray bar
// reaches them, as the tracker knows it. The plants leaving the view's near
// edge now reach the bar after the vehicle drives on from there to the bar;
// the grid's covariance predicted over that distance by dead reckoning
// (GridTracker::PredictAhead, eq. 4.3 with its process noise) gives the
// covariance of each row's plant at the bar, C = J P Jᵀ with J the grid
// plant's Jacobian (eq. A.1, geometry::PlantInVehicleJacobian). Its 95 %
// ellipse {p : pᵀ C⁻¹ p ≤ χ²₂(0.95) = 5.991} reaches √(5.991 C_yy) along
// the rows and √(5.991 C_xx) across them: it fits in a footprint of those
// half sizes about the plant, and a spray that reaches less far past the
// plant may miss it. The nozzle scheduler closes the bar while the reach
// exceeds the footprint's margin (FailSafeOptions::max_reach_*).

#include <Eigen/Core>

#include "engine/geometry/grid_model.h"
#include "engine/tracking/grid_tracker.h"

namespace plantscale::treatment {

// χ² with 2 degrees of freedom at 95 %.
inline constexpr double kChi2TwoDof95 = 5.991;

struct PlantReach {
  double across_m = 0.0;  // half extent of the 95 % ellipse across the rows (vehicle x)
  double along_m = 0.0;   // along the rows (vehicle y)
  double ahead_m = 0.0;   // the distance the grid was predicted over
};

// Half extents of the ellipse pᵀ C⁻¹ p ≤ chi2 along the frame's axes.
PlantReach EllipseReach(const Eigen::Matrix2d& covariance, double chi2 = kChi2TwoDof95);

// The line of row n whose plant stands nearest vehicle y = bar_y_m in the
// grid `state` (eq. A.1 solved for m).
int LineAt(const geometry::GridState& state, int n, double bar_y_m);

// The covariance of row n's plant at vehicle y = bar_y_m, grid covariance `p`.
Eigen::Matrix2d PlantCovarianceAt(const geometry::GridState& state, const geometry::Matrix5d& p,
                                  int n, double bar_y_m);

// The worst reach over the bed's rows (−k..k, TrackerOptions::rows_each_side)
// of the plants now at vehicle y = view_near_y_m once they reach the bar at
// vehicle y = −bar_offset_m, predicted in increments of step_m. Zero when
// the tracker does not hold the grid (the bar is closed for that already).
PlantReach PlantReachAtBar(const tracking::GridTracker& tracker, double view_near_y_m,
                           double bar_offset_m, double step_m);

}  // namespace plantscale::treatment
