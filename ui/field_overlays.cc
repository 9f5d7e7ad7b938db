#include "ui/field_overlays.h"

#include <cmath>
#include <stdexcept>

#include "ui/palette.h"

namespace plantscale::ui {
namespace {

namespace tm = plantscale::telemetry;

// Thesis eq. A.1 with a real-valued row index n and line index m: grid point
// (n r̄, m l̄ + Y) in the vehicle frame.
Eigen::Vector2d GridPoint(const geometry::GridState& g, double m, double n) {
  const double c = std::cos(g.bearing_rad), s = std::sin(g.bearing_rad);
  const double gx = n * g.row_spacing_m, gy = m * g.plant_spacing_m + g.forward_m;
  return {c * gx + s * gy + g.offset_m, -s * gx + c * gy};
}

const tm::GridEstimate* GridOf(const review::RunModel& model) {
  if (model.grid()) return &*model.grid();
  return model.truth() ? &*model.truth() : nullptr;
}

}  // namespace

Eigen::Vector2d VehicleToField(const tm::Pose& pose, const Eigen::Vector2d& v) {
  const double c = std::cos(pose.heading_rad), s = std::sin(pose.heading_rad);
  return {pose.x_m + c * v.x() - s * v.y(), pose.y_m + s * v.x() + c * v.y()};
}

std::vector<Polyline> GridRowLines(const tm::GridEstimate& grid, const tm::Pose& pose,
                                   const GridOverlayParams& p) {
  std::vector<Polyline> out;
  for (int n = -p.rows_each_side; n <= p.rows_each_side; ++n) {
    out.push_back({VehicleToField(pose, GridPoint(grid.state, -p.lines_behind, n)),
                   VehicleToField(pose, GridPoint(grid.state, p.lines_ahead, n))});
  }
  return out;
}

std::vector<Polyline> GridPlantLines(const tm::GridEstimate& grid, const tm::Pose& pose,
                                     const GridOverlayParams& p) {
  std::vector<Polyline> out;
  const double half = p.rows_each_side + 0.5;
  for (int m = -p.lines_behind; m <= p.lines_ahead; ++m) {
    out.push_back({VehicleToField(pose, GridPoint(grid.state, m, -half)),
                   VehicleToField(pose, GridPoint(grid.state, m, half))});
  }
  return out;
}

GridOverlay::GridOverlay(const GridOverlayParams& params)
    : params_(params), rows_(palette::kRowLine, 2.0, 0.05), lines_(palette::kPlantLine, 1.0, 0.04) {}

void GridOverlay::AddTo(vtkRenderer* renderer) {
  rows_.AddTo(renderer);
  lines_.AddTo(renderer);
}

void GridOverlay::Update(const review::RunModel& model) {
  if (!built_.Changed(model)) return;
  const tm::GridEstimate* grid = GridOf(model);
  const std::optional<tm::Pose> pose = model.pose();
  if (grid == nullptr || !pose) {
    rows_.Set({});
    lines_.Set({});
    return;
  }
  rows_.Set(GridRowLines(*grid, *pose, params_));
  lines_.Set(GridPlantLines(*grid, *pose, params_));
}

void GridOverlay::SetVisible(bool visible) {
  rows_.SetVisible(visible);
  lines_.SetVisible(visible);
}

std::optional<Eigen::Matrix2d> VehicleCovariance(const review::RunModel& model, const tm::Pose& pose) {
  const Eigen::Matrix2d own = pose.covariance.topLeftCorner<2, 2>();
  if (own.trace() > 0.0) return own;
  const tm::GridEstimate* grid = GridOf(model);
  if (grid == nullptr) return std::nullopt;
  const Eigen::Matrix2d c = grid->covariance.topLeftCorner<2, 2>();  // offset (across), forward (along)
  if (!(c.trace() > 0.0)) return std::nullopt;
  const double cs = std::cos(pose.heading_rad), sn = std::sin(pose.heading_rad);
  Eigen::Matrix2d r;
  r << cs, -sn, sn, cs;  // vehicle → field, as VehicleToField
  return r * c * r.transpose();
}

CovarianceEllipses::CovarianceEllipses(const EllipseParams& params)
    : params_(params),
      k2_(review::EllipseScale2d(params.confidence)),
      vehicle_(palette::kVehicle, 2.0, 0.07),
      plants_(palette::kPlantEllipse, 1.0, 0.06) {
  SetMagnification(params.magnification);
}

void CovarianceEllipses::AddTo(vtkRenderer* renderer) {
  vehicle_.AddTo(renderer);
  plants_.AddTo(renderer);
}

void CovarianceEllipses::SetConfidence(double confidence) {
  k2_ = review::EllipseScale2d(confidence);
  params_.confidence = confidence;
  seen_messages_ = -1;
  seen_plants_ = -1;
}

void CovarianceEllipses::SetMagnification(double magnification) {
  if (!(magnification > 0.0)) throw std::invalid_argument("ellipse magnification must be > 0");
  params_.magnification = magnification;
  seen_messages_ = -1;
  seen_plants_ = -1;
}

void CovarianceEllipses::Update(const review::RunModel& model, const FieldWindow& view) {
  if (model.messages() != seen_messages_) {
    seen_messages_ = model.messages();
    const std::optional<tm::Pose> pose = model.pose();
    std::vector<Polyline> vehicle;
    const std::optional<Eigen::Matrix2d> cov = pose ? VehicleCovariance(model, *pose) : std::nullopt;
    if (cov) vehicle.push_back(EllipseOutline({pose->x_m, pose->y_m}, *cov, DrawnK2()));
    vehicle_.Set(vehicle);
    drew_vehicle_ = cov.has_value();
  }
  if (model.plant_messages() == seen_plants_ && built_.Covers(view)) return;
  seen_plants_ = model.plant_messages();
  built_ = BuiltRange::Around(view, 0.5 * (view.y1_m - view.y0_m));
  std::vector<Polyline> plants;
  const bool close = view.y1_m - view.y0_m <= params_.max_view_m;
  // Newest first, at most max_plants of those near the view.
  for (auto it = model.plants().rbegin();
       close && it != model.plants().rend() && static_cast<int>(plants.size()) < params_.max_plants; ++it) {
    const tm::PlantObservation& p = it->second.plant;
    if (p.position_m.y() < built_.y0_m || p.position_m.y() > built_.y1_m) continue;
    if (p.covariance.trace() > 0.0) plants.push_back(EllipseOutline(p.position_m, p.covariance, DrawnK2(), 24));
  }
  plants_.Set(plants);
  drew_plants_ = !plants.empty();
}

void CovarianceEllipses::SetVisible(bool visible) {
  vehicle_.SetVisible(visible);
  plants_.SetVisible(visible);
}

void PlantMarkers::Update(const review::RunModel& model, const FieldWindow& view) {
  if (model.plant_messages() == seen_messages_ && built_.Covers(view)) return;
  seen_messages_ = model.plant_messages();
  built_ = BuiltRange::Around(view, 0.5 * (view.y1_m - view.y0_m));
  std::vector<Eigen::Vector2d> points;
  std::vector<Rgb> colours;
  for (const auto& [id, r] : model.plants()) {
    if (r.plant.position_m.y() < built_.y0_m || r.plant.position_m.y() > built_.y1_m) continue;
    points.push_back(r.plant.position_m);
    colours.push_back(r.plant.kind == tm::PlantKind::kCrop   ? palette::kCrop
                      : r.plant.kind == tm::PlantKind::kWeed ? palette::kWeed
                                                             : palette::kUnknownPlant);
  }
  points_.Set(points, colours);
}

VehicleMarker::VehicleMarker() : body_(palette::kVehicle, 3.0, 0.08), path_(palette::kPath, 1.0, 0.03) {}

void VehicleMarker::AddTo(vtkRenderer* renderer) {
  body_.AddTo(renderer);
  path_.AddTo(renderer);
}

void VehicleMarker::Update(const review::RunModel& model) {
  if (!built_.Changed(model)) return;
  const std::optional<tm::Pose> pose = model.pose();
  if (!pose) return;
  // A 0.3 m arrowhead pointing along the vehicle's forward (y) axis.
  body_.Set({{VehicleToField(*pose, {-0.12, -0.15}), VehicleToField(*pose, {0.0, 0.15}),
              VehicleToField(*pose, {0.12, -0.15}), VehicleToField(*pose, {-0.12, -0.15})}});
  Polyline path;
  const auto& p = model.path();
  const size_t step = std::max<size_t>(1, p.size() / 2000);
  for (size_t i = 0; i < p.size(); i += step) path.emplace_back(p[i].first, p[i].second);
  path_.Set({path});
}

void VehicleMarker::SetVisible(bool visible) {
  body_.SetVisible(visible);
  path_.SetVisible(visible);
}

}  // namespace plantscale::ui
