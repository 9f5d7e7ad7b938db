#pragma once
// The heading of the crop rows in the first frame's vehicle frame, learned
// from the plants the motion recovery maps (issue 7, our method).
//
// Without odometry the rotation between consecutive frames is the weak part
// of the motion, and the composed heading wanders. The vehicle steers along
// the rows, so the rows are the heading it returns to. The first frame's
// heading is not it (the vehicle zig-zags about the row: ±0.9° on the Sanchiz
// & Pla presets), so the rows' direction is measured on the map: crop plant
// positions mapped into the world are kept for the last `memory_m` driven;
//   1. Hough: the heading whose rows are sharpest, i.e. that maximises the
//      sum of squares of the histogram of x + tan H·y (1 cm bins), over
//      ±max_angle_rad, coarse then fine;
//   2. rows are that histogram's peaks; one direction is fitted to all rows at
//      once, x = a_row + s·y by weighted least squares with an intercept per
//      row (pooled within-row regression), points farther than `gate_m` from
//      their row's line left out, three times.
// The fitted heading is fused with the belief that the first frame points
// along the rows (σ `initial_sigma_rad`), each by its precision
// (σ_fit² = scatter_m² / Σ_rows Σ w (y − ȳ_row)²; weights count plants, not
// sightings).

#include <Eigen/Core>
#include <deque>
#include <vector>

#include "engine/common/options.h"

namespace plantscale::motion {

struct RowHeadingOptions {
  double bin_m = 0.01;             // histogram bin of the Hough sharpness
  double max_angle_rad = 3.0 * M_PI / 180.0;  // rows searched within this of the first frame's heading
  double coarse_step_rad = 0.2 * M_PI / 180.0;
  double fine_step_rad = 0.02 * M_PI / 180.0;
  double peak_fraction = 0.3;      // rows: histogram peaks (2 bins wide) above this share of the highest
  double gate_m = 0.035;           // points this far across from their row's line are not the row's
  double scatter_m = 0.02;         // σ of a plant's mapped position across its row
  double initial_sigma_rad = 0.7 * M_PI / 180.0;  // σ of the first frame's heading off the rows
  double memory_m = 20.0;          // plants mapped longer ago than this are forgotten
  double refit_every_m = 0.05;     // the fit is redone after this much driving
  double max_half_width_m = 10.0;  // points farther across than this from the median are ignored

  OptionErrors Validate() const;
};

struct RowHeadingFit {
  double heading_rad = 0.0;  // of the rows, from the map alone
  double sigma_rad = 0.0;    // infinite when no row has spread along y
  int rows = 0;
  double weight = 0.0;       // of the points in the rows
};

// The fit of step 1–2 on points (x, y) with weights; non-finite points and
// points more than max_half_width_m across from the median are ignored.
RowHeadingFit FitRowHeading(const std::vector<Eigen::Vector3d>& points_xyw,
                            const RowHeadingOptions& options);

class RowHeading {
 public:
  explicit RowHeading(const RowHeadingOptions& options);

  // Distance driven since the last call (forgets old plants, schedules a refit).
  void Drive(double distance_m);
  // One mapped plant position (world frame: x across, y along the first
  // frame's forward axis); `weight` is the share of the plant this sighting is.
  void Add(const Eigen::Vector2d& world_m, double weight = 1.0);

  // The vehicle heading (VehiclePose2::heading_rad) that drives along the
  // rows: the fitted direction fused with the first frame's (0).
  double heading_rad();
  const RowHeadingFit& fit();

 private:
  struct Point {
    Eigen::Vector3d xyw;
    double odometer_m;
  };
  RowHeadingOptions options_;
  std::deque<Point> points_;
  double odometer_m_ = 0.0;
  double fitted_at_m_ = -1.0;
  bool changed_ = false;
  RowHeadingFit fit_;
};

}  // namespace plantscale::motion
