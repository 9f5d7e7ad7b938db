#pragma once
// Row-fit evaluation of a mosaic (Sanchiz & Pla §5): plant centres are
// assigned to rows, a straight line is fitted to each row, and the map's
// accuracy is read from the RMS distance of the plants to their line, the
// angle between neighbouring lines and their spacing at the centre of the
// map. The paper assigned plants to rows by hand; here rows are gaps in the
// across-row coordinate (rows run along y).

#include <Eigen/Core>
#include <span>
#include <vector>

#include "engine/common/options.h"

namespace plantscale::motion {

struct RowFitOptions {
  double row_gap_m = 0.15;  // a gap this wide in x starts a new row
  int min_plants = 3;       // rows with fewer plants are not fitted
  // Plants farther than this from the first fit are not the row's (weeds
  // taken for crop, merged blobs; the paper assigned plants by hand) and the
  // line is fitted again without them. 0: keep every plant.
  double outlier_m = 0.06;

  OptionErrors Validate() const;
};

struct FittedLine {
  Eigen::Vector2d point_m{0.0, 0.0};      // centroid of the row's plants
  Eigen::Vector2d direction{0.0, 1.0};    // unit, y ≥ 0
  double rms_m = 0.0;                     // perpendicular distances
  int plants = 0;
  int outliers = 0;                       // plants left out of the fit
  // Across-row x of the line at height y.
  double XAt(double y_m) const;
};

// Total least squares line through points (perpendicular residuals).
FittedLine FitLine(std::span<const Eigen::Vector2d> points);

struct RowFit {
  std::vector<FittedLine> rows;        // left to right
  std::vector<double> angles_rad;      // between neighbouring rows
  std::vector<double> spacings_m;      // between neighbouring rows at centre_y
  double mean_rms_m = 0.0;
  double mean_angle_rad = 0.0;
  double mean_spacing_m = 0.0;         // 0 with fewer than two rows
};

// Rows from plant centres; spacings are measured at y = centre_y_m,
// perpendicular to the mean direction of the two lines.
RowFit FitRows(std::span<const Eigen::Vector2d> plants_m, double centre_y_m,
               const RowFitOptions& options);

}  // namespace plantscale::motion
