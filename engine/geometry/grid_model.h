#pragma once
// The crop grid (thesis §2.2, eqs. 2.1–2.2; ch. 4): plants of row n and
// plant line m sit at grid coordinates (n·r̄, m·l̄ + Y), rotated by the
// bearing Ψ and offset by t_x into the vehicle frame (thesis eq. A.1):
//
//   x_v =  cos Ψ · n r̄ + sin Ψ · (m l̄ + Y) + t_x
//   y_v = −sin Ψ · n r̄ + cos Ψ · (m l̄ + Y)
//
// Row n = 0 is the central row; rows are numbered left to right. Line m = 0
// is the bottom-most plant line in view and m grows forward (up the image).
// Conventions (docs/design.md §3): t_x is where the central row crosses the
// vehicle's x axis (positive: the row is to the right of the camera), Y is
// the forward distance from the vehicle origin to line 0, Ψ is the
// vehicle's heading relative to the rows, counter-clockwise positive.

#include <Eigen/Core>
#include <optional>
#include <vector>

#include "engine/common/options.h"
#include "engine/geometry/camera_model.h"

namespace plantscale::geometry {

using Vector5d = Eigen::Matrix<double, 5, 1>;
using Matrix5d = Eigen::Matrix<double, 5, 5>;

// The estimated-grid state of thesis §4.1.2, in its order (t_x, Y, Ψ, r̄, l̄).
struct GridState {
  double offset_m = 0.0;          // t_x
  double forward_m = 0.0;         // Y
  double bearing_rad = 0.0;       // Ψ
  double row_spacing_m = 0.475;   // r̄
  double plant_spacing_m = 0.45;  // l̄

  enum Index { kOffset = 0, kForward = 1, kBearing = 2, kRowSpacing = 3, kPlantSpacing = 4 };
  Vector5d AsVector() const;
  static GridState FromVector(const Vector5d& x);
};

// Ground position (vehicle frame) of grid plant (m, n).
Eigen::Vector2d PlantInVehicle(const GridState& state, int m, int n);
// d(x_v, y_v) / d(t_x, Y, Ψ, r̄, l̄).
Eigen::Matrix<double, 2, 5> PlantInVehicleJacobian(const GridState& state, int m, int n);

struct GridModelOptions {
  int rows_each_side = 1;    // rows n = −k..k; the thesis bed has 3 rows
  double max_range_m = 6.0;  // lines beyond this forward distance are ignored
  double in_view_margin_px = 0.0;

  OptionErrors Validate() const;
};

struct GridPlant {
  int m = 0;
  int n = 0;
  Eigen::Vector2d ground_m;  // vehicle frame, on the plane the model projects to
  Eigen::Vector2d image_px;
};

class GridModel {
 public:
  // Plants are projected onto the camera's virtual ground plane.
  GridModel(const CameraModel& camera, const GridModelOptions& options);

  const CameraModel& camera() const { return camera_; }
  const GridModelOptions& options() const { return options_; }

  // Thesis eq. 4.12 (h(x, m, n)) without the small-angle approximation.
  std::optional<Eigen::Vector2d> ImageOfPlant(const GridState& state, int m, int n) const;
  // Thesis eqs. 4.18–4.27: d(u, v) / d(t_x, Y, Ψ, r̄, l̄).
  Eigen::Matrix<double, 2, 5> ImageOfPlantJacobian(const GridState& state, int m, int n) const;
  // Every grid plant whose projection lies inside the image, line by line
  // (PlantsReachingView with no reach).
  std::vector<GridPlant> PlantsInView(const GridState& state) const;
  // Those and the plants whose leaves may reach into the view from beyond
  // its border: the root, or a point `reach_m` from it along x or y on the
  // virtual plane, projects into the image (uv: the root's image, which may
  // lie outside it).
  std::vector<GridPlant> PlantsReachingView(const GridState& state, double reach_m) const;
  bool LineInView(const GridState& state, int m) const;

  // The change of reference of thesis eq. 4.6: while line 0 has left the
  // bottom of the image, Y ← Y + l̄ (and the reverse when the vehicle backs
  // up). Returns the number of lines shifted (positive forward).
  int ShiftReference(GridState& state) const;
  // State transition of that shift for the estimated-grid filter (eq. 4.8):
  // identity with A(Y, l̄) = lines.
  static Matrix5d ReferenceShiftTransition(int lines);

 private:
  bool BelowImage(const GridState& state, int m) const;

  CameraModel camera_;
  GridModelOptions options_;
};

}  // namespace plantscale::geometry
