#pragma once
// Fail-safe on uncertainty: where the plants the spray bar now reaches
// stand, as the tracker knows it. The treatment map lives in the bed frame,
// which is the tracker's grid (bed_frame.h: bed y = l̄ × lines passed − Y),
// and each crop footprint stands at its plant's grid position: the plants
// reaching the bar were mapped from frames that saw them, and the bar is
// placed on the map by the grid as the tracker holds it now. What the spray
// misses by is therefore the error of the grid now at the bar, driven on by
// dead reckoning only over the time until the spray lands (the valves'
// latency and one pose period), not over the 1–2 m from the view to the bar:
// frames keep correcting the grid while the plants travel there, and when
// they stop, the filter's covariance grows by its process noise with every
// metre coasted, which is what this reads. GridTracker::PredictAhead (eq. 4.3
// with its process noise) predicts the grid over that short distance; each
// row's plant at the bar has covariance C = J P Jᵀ with J the grid plant's
// Jacobian (eq. A.1, geometry::PlantInVehicleJacobian). Its 95 % ellipse
// {p : pᵀ C⁻¹ p ≤ χ²₂(0.95) = 5.991} reaches √(5.991 C_yy) along the rows
// and √(5.991 C_xx) across them. The nozzle scheduler closes the bar while
// the reach exceeds how far the sprayed footprint extends beyond the plant's
// root (FailSafeOptions::max_reach_*, TreatmentOptions::UncertaintyMargin).

#include <Eigen/Core>

#include "engine/geometry/grid_model.h"
#include "engine/tracking/grid_tracker.h"

namespace plantscale::treatment {

// χ² with 2 degrees of freedom at 95 %.
inline constexpr double kChi2TwoDof95 = 5.991;

struct PlantReach {
  double across_m = 0.0;  // half extent of the 95 % ellipse across the rows (vehicle x)
  double along_m = 0.0;   // along the rows (vehicle y)
  double ahead_m = 0.0;   // the distance the grid was predicted over (dead reckoning)
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
// of the plants at the bar (vehicle y = −bar_offset_m), the grid predicted
// ahead_m by dead reckoning in increments of step_m. Zero when the tracker
// does not hold the grid (the bar is closed for that already).
PlantReach PlantReachAtBar(const tracking::GridTracker& tracker, double ahead_m,
                           double bar_offset_m, double step_m);

}  // namespace plantscale::treatment
