#include "ui/map_view.h"

#include <vtkCamera.h>
#include <vtkCoordinate.h>
#include <vtkNew.h>

#include <algorithm>

namespace plantscale::ui {

MapView::MapView(const MapViewParams& params)
    : params_(params), grid_(params.grid), ellipses_(params.ellipses) {}

void MapView::AddTo(vtkRenderer* renderer) {
  renderer_ = renderer;
  map_.AddTo(renderer);
  plants_.AddTo(renderer);
  grid_.AddTo(renderer);
  ellipses_.AddTo(renderer);
  vehicle_.AddTo(renderer);
  vtkCamera* camera = renderer->GetActiveCamera();
  camera->ParallelProjectionOn();
  camera->SetViewUp(-1.0, 0.0, 0.0);  // field −x up, so field +y runs to the right
}

void MapView::Update(const RunModel& model) {
  map_.Update(model);
  const FieldWindow view = PlaceCamera(model);
  map_.Cull(view);
  plants_.Update(model, view);
  grid_.Update(model);
  ellipses_.Update(model, view);
  vehicle_.Update(model);
}

FieldWindow MapView::WholeRun(const RunModel& model) const {
  double lo = 1e300, hi = -1e300;
  for (const auto& [x, y] : model.path()) lo = std::min(lo, y), hi = std::max(hi, y);
  for (const auto& [id, r] : model.plants()) {
    lo = std::min(lo, r.plant.position_m.y()), hi = std::max(hi, r.plant.position_m.y());
  }
  double b[4];
  if (map_.Bounds(b)) lo = std::min(lo, b[2]), hi = std::max(hi, b[3]);
  if (lo > hi) return {};
  return {lo - 0.2, hi + 0.2, 0.0};
}

FieldWindow MapView::PlaceCamera(const RunModel& model) {
  FieldWindow w;
  if (window_) {
    w = *window_;
  } else if (const auto pose = model.pose()) {
    const double start = pose->y_m - (0.5 * params_.follow_length_m - params_.follow_ahead_m);
    w = {start, start + params_.follow_length_m, 0.0};
  }
  if (renderer_ == nullptr) return w;
  // Parallel scale is half the view height; the height holds length / aspect.
  const double aspect = std::max(1e-6, renderer_->GetTiledAspectRatio());
  const std::array<double, 4> placed = {w.y0_m, w.y1_m, w.x_centre_m, aspect};
  if (placed == placed_) return w;  // the camera is where it was: leave it unmodified
  placed_ = placed;
  const double cy = 0.5 * (w.y0_m + w.y1_m);
  vtkCamera* camera = renderer_->GetActiveCamera();
  camera->SetFocalPoint(w.x_centre_m, cy, 0.0);
  camera->SetPosition(w.x_centre_m, cy, 50.0);
  camera->SetViewUp(-1.0, 0.0, 0.0);
  camera->SetParallelScale(std::max(0.5 * params_.min_across_m, 0.5 * (w.y1_m - w.y0_m) / aspect));
  camera->SetClippingRange(1.0, 100.0);
  return w;
}

void MapView::SetVisible(MapLayerId layer, bool visible) {
  visible_[static_cast<int>(layer)] = visible;
  switch (layer) {
    case MapLayerId::kMap:
      return map_.SetVisible(visible);
    case MapLayerId::kPlants:
      return plants_.SetVisible(visible);
    case MapLayerId::kGrid:
      return grid_.SetVisible(visible);
    case MapLayerId::kEllipses:
      return ellipses_.SetVisible(visible);
    case MapLayerId::kVehicle:
      return vehicle_.SetVisible(visible);
  }
}

bool MapView::Visible(MapLayerId layer) const { return visible_[static_cast<int>(layer)]; }

Eigen::Vector2d MapView::DisplayAtField(const Eigen::Vector2d& field) const {
  vtkNew<vtkCoordinate> c;
  c->SetCoordinateSystemToWorld();
  c->SetValue(field.x(), field.y(), 0.0);
  const double* display = c->GetComputedDoubleDisplayValue(renderer_);
  return {display[0], display[1]};
}

Eigen::Vector2d MapView::FieldAtDisplay(double x, double y) const {
  vtkNew<vtkCoordinate> c;
  c->SetCoordinateSystemToDisplay();
  c->SetValue(x, y, 0.0);
  const double* world = c->GetComputedWorldValue(renderer_);
  return {world[0], world[1]};
}

}  // namespace plantscale::ui
