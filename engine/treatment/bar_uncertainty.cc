#include "engine/treatment/bar_uncertainty.h"

#include <algorithm>
#include <cmath>

namespace plantscale::treatment {

PlantReach EllipseReach(const Eigen::Matrix2d& c, double chi2) {
  PlantReach r;
  r.across_m = std::sqrt(chi2 * std::max(0.0, c(0, 0)));
  r.along_m = std::sqrt(chi2 * std::max(0.0, c(1, 1)));
  return r;
}

int LineAt(const geometry::GridState& s, int n, double bar_y_m) {
  // Eq. A.1: y_v = −sin Ψ · n r̄ + cos Ψ · (m l̄ + Y).
  const double along = (bar_y_m + std::sin(s.bearing_rad) * n * s.row_spacing_m) /
                       std::cos(s.bearing_rad);
  return static_cast<int>(std::lround((along - s.forward_m) / s.plant_spacing_m));
}

Eigen::Matrix2d PlantCovarianceAt(const geometry::GridState& s, const geometry::Matrix5d& p,
                                  int n, double bar_y_m) {
  const Eigen::Matrix<double, 2, 5> j = geometry::PlantInVehicleJacobian(s, LineAt(s, n, bar_y_m), n);
  return j * p * j.transpose();
}

PlantReach PlantReachAtBar(const tracking::GridTracker& tracker, double ahead_m,
                           double bar_offset_m, double step_m) {
  PlantReach worst;
  if (tracker.mode() != tracking::TrackerMode::kTracking) return worst;
  worst.ahead_m = std::max(0.0, ahead_m);
  const tracking::GridAhead ahead = tracker.PredictAhead(worst.ahead_m, step_m);
  const int k = tracker.options().rows_each_side;
  for (int n = -k; n <= k; ++n) {
    const PlantReach r = EllipseReach(PlantCovarianceAt(ahead.state, ahead.covariance, n, -bar_offset_m));
    worst.across_m = std::max(worst.across_m, r.across_m);
    worst.along_m = std::max(worst.along_m, r.along_m);
  }
  return worst;
}

}  // namespace plantscale::treatment
