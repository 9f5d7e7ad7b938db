#include "engine/geometry/grid_model.h"

#include <cmath>

namespace plantscale::geometry {

Vector5d GridState::AsVector() const {
  Vector5d x;
  x << offset_m, forward_m, bearing_rad, row_spacing_m, plant_spacing_m;
  return x;
}

GridState GridState::FromVector(const Vector5d& x) {
  return GridState{x(kOffset), x(kForward), x(kBearing), x(kRowSpacing), x(kPlantSpacing)};
}

Eigen::Vector2d PlantInVehicle(const GridState& s, int m, int n) {
  const double c = std::cos(s.bearing_rad);
  const double si = std::sin(s.bearing_rad);
  const double gx = n * s.row_spacing_m;                  // eq. 2.1
  const double gy = m * s.plant_spacing_m + s.forward_m;  // eq. 2.2
  return {c * gx + si * gy + s.offset_m, -si * gx + c * gy};
}

Eigen::Matrix<double, 2, 5> PlantInVehicleJacobian(const GridState& s, int m, int n) {
  const double c = std::cos(s.bearing_rad);
  const double si = std::sin(s.bearing_rad);
  const double gx = n * s.row_spacing_m;
  const double gy = m * s.plant_spacing_m + s.forward_m;
  Eigen::Matrix<double, 2, 5> j;
  //     t_x  Y    Ψ                  r̄        l̄
  j << 1.0, si, -si * gx + c * gy, c * n, si * m,  //
      0.0, c, -c * gx - si * gy, -si * n, c * m;
  return j;
}

OptionErrors GridModelOptions::Validate() const {
  OptionErrors errors;
  if (rows_each_side < 0 || rows_each_side > 20) {
    errors.push_back({"rows_each_side", "must be in [0, 20]"});
  }
  RequirePositive(errors, "max_range_m", max_range_m);
  RequireNonNegative(errors, "in_view_margin_px", in_view_margin_px);
  return errors;
}

GridModel::GridModel(const CameraModel& camera, const GridModelOptions& options)
    : camera_(camera), options_(options) {
  ThrowIfInvalid("grid model", options.Validate());
}

std::optional<Eigen::Vector2d> GridModel::ImageOfPlant(const GridState& state, int m, int n) const {
  const Eigen::Vector2d g = PlantInVehicle(state, m, n);
  return camera_.Project({g.x(), g.y(), camera_.options().virtual_plane_height_m});
}

Eigen::Matrix<double, 2, 5> GridModel::ImageOfPlantJacobian(const GridState& state, int m,
                                                            int n) const {
  // Chain rule: d(u,v)/d(x_v,y_v) (plane height fixed) · d(x_v,y_v)/d(state).
  const Eigen::Vector2d g = PlantInVehicle(state, m, n);
  const Eigen::Matrix<double, 2, 3> d_uv_d_p =
      camera_.ProjectJacobian({g.x(), g.y(), camera_.options().virtual_plane_height_m});
  return d_uv_d_p.leftCols<2>() * PlantInVehicleJacobian(state, m, n);
}

bool GridModel::LineInView(const GridState& state, int m) const {
  for (int n = -options_.rows_each_side; n <= options_.rows_each_side; ++n) {
    const auto uv = ImageOfPlant(state, m, n);
    if (uv && camera_.InImage(*uv, options_.in_view_margin_px)) return true;
  }
  return false;
}

std::vector<GridPlant> GridModel::PlantsInView(const GridState& state) const {
  return PlantsReachingView(state, 0.0);
}

std::vector<GridPlant> GridModel::PlantsReachingView(const GridState& state,
                                                     double reach_m) const {
  std::vector<GridPlant> plants;
  const double h = camera_.options().virtual_plane_height_m;
  const auto in_image = [&](const Eigen::Vector2d& g) {
    const auto uv = camera_.Project({g.x(), g.y(), h});
    return uv && camera_.InImage(*uv, options_.in_view_margin_px);
  };
  // Line 0 is the first not below the image (ShiftReference); a line
  // further back may still reach into it.
  const int back = static_cast<int>(std::ceil(reach_m / std::max(state.plant_spacing_m, 1e-3)));
  for (int m = -back;; ++m) {
    const Eigen::Vector2d centre = PlantInVehicle(state, m, 0);
    if (centre.y() - reach_m > options_.max_range_m || m > 1000) break;
    for (int n = -options_.rows_each_side; n <= options_.rows_each_side; ++n) {
      const Eigen::Vector2d g = PlantInVehicle(state, m, n);
      const auto uv = ImageOfPlant(state, m, n);
      bool near = uv && camera_.InImage(*uv, options_.in_view_margin_px);
      if (!near && reach_m > 0.0) {
        for (const Eigen::Vector2d& d : {Eigen::Vector2d(reach_m, 0.0), Eigen::Vector2d(-reach_m, 0.0),
                                        Eigen::Vector2d(0.0, reach_m), Eigen::Vector2d(0.0, -reach_m)}) {
          near = near || in_image(g + d);
        }
      }
      if (near) plants.push_back({m, n, g, uv ? *uv : Eigen::Vector2d(std::nan(""), std::nan(""))});
    }
  }
  return plants;
}

bool GridModel::BelowImage(const GridState& state, int m) const {
  // Thesis §4.1.3 footnote 3: project the line's central-row plant and test
  // it against the image bounds.
  const Eigen::Vector2d g = PlantInVehicle(state, m, 0);
  const auto uv = camera_.Project({g.x(), g.y(), camera_.options().virtual_plane_height_m});
  return !uv || uv->y() > camera_.height();
}

int GridModel::ShiftReference(GridState& state) const {
  int shifted = 0;
  while (BelowImage(state, 0) && shifted < 1000) {
    state.forward_m += state.plant_spacing_m;
    ++shifted;
  }
  if (shifted > 0) return shifted;
  while (!BelowImage(state, -1) && shifted > -1000) {
    state.forward_m -= state.plant_spacing_m;
    --shifted;
  }
  return shifted;
}

Matrix5d GridModel::ReferenceShiftTransition(int lines) {
  Matrix5d a = Matrix5d::Identity();
  a(GridState::kForward, GridState::kPlantSpacing) = lines;
  return a;
}

}  // namespace plantscale::geometry
