#include "ui/map_view.h"

#include <vtkCamera.h>
#include <vtkCoordinate.h>
#include <vtkNew.h>

#include <algorithm>
#include <utility>

#include "ui/palette.h"

namespace plantscale::ui {

namespace {

constexpr double kMinViewM = 0.3, kMaxViewM = 20000.0;  // along-bed lengths a zoom stops at

}  // namespace

MapView::MapView(const MapViewParams& params)
    : params_(params),
      grid_(params.grid),
      ellipses_(params.ellipses),
      pick_(palette::kPick, 3.0, 0.2),
      measure_(palette::kPick, 3.0, 0.2),
      follow_length_m_(params.follow_length_m) {}

void MapView::AddTo(vtkRenderer* renderer) {
  renderer_ = renderer;
  map_.AddTo(renderer);
  plants_.AddTo(renderer);
  grid_.AddTo(renderer);
  ellipses_.AddTo(renderer);
  vehicle_.AddTo(renderer);
  pick_.AddTo(renderer);
  measure_.AddTo(renderer);
  vtkCamera* camera = renderer->GetActiveCamera();
  camera->ParallelProjectionOn();
  camera->SetViewUp(-1.0, 0.0, 0.0);  // field −x up, so field +y runs to the right
}

void MapView::Update(const review::RunModel& model) {
  const FieldWindow view = PlaceCamera(model);
  map_.Update(model, view);
  plants_.Update(model, view);
  grid_.Update(model);
  ellipses_.Update(model, view);
  vehicle_.Update(model);
  if (metres_per_pixel() != marks_mpp_) DrawMarks();
}

void MapView::Zoom(double factor, std::optional<double> about_y_m) {
  if (!(factor > 0.0)) return;
  if (!window_) {
    follow_length_m_ = std::clamp(follow_length_m_ / factor, kMinViewM, kMaxViewM);
    return;
  }
  FieldWindow& w = *window_;
  const double length = std::clamp((w.y1_m - w.y0_m) / factor, kMinViewM, kMaxViewM);
  const double about = about_y_m.value_or(0.5 * (w.y0_m + w.y1_m));
  // The point under `about` stays where it is on the screen.
  const double t = w.y1_m > w.y0_m ? (about - w.y0_m) / (w.y1_m - w.y0_m) : 0.5;
  w.y0_m = about - t * length;
  w.y1_m = w.y0_m + length;
}

void MapView::Pan(double along_m, double across_m) {
  if (!window_) window_ = view_;
  window_->y0_m += along_m, window_->y1_m += along_m;
  window_->x_centre_m += across_m;
}

double MapView::metres_per_pixel() const {
  if (renderer_ == nullptr || renderer_->GetSize()[1] <= 0) return 0.0;
  return 2.0 * renderer_->GetActiveCamera()->GetParallelScale() / renderer_->GetSize()[1];
}

void MapView::SetMarks(std::optional<Eigen::Vector2d> pick, std::vector<Eigen::Vector2d> measure) {
  if (pick == pick_at_ && measure == measure_at_) return;
  pick_at_ = pick, measure_at_ = std::move(measure);
  DrawMarks();
}

// A ring 12 px across the pick and a cross at it; the measured line with a
// tick across each end (sized in pixels: they read the same at any zoom).
void MapView::DrawMarks() {
  marks_mpp_ = metres_per_pixel();
  const double px = marks_mpp_ > 0 ? marks_mpp_ : 0.005;
  std::vector<Polyline> ring, line;
  if (pick_at_) {
    ring.push_back(EllipseOutline(*pick_at_, Eigen::Matrix2d::Identity(), (12 * px) * (12 * px), 32));
  }
  for (const Eigen::Vector2d& p : measure_at_) {
    line.push_back({p + Eigen::Vector2d(-6 * px, -6 * px), p + Eigen::Vector2d(6 * px, 6 * px)});
    line.push_back({p + Eigen::Vector2d(-6 * px, 6 * px), p + Eigen::Vector2d(6 * px, -6 * px)});
  }
  if (measure_at_.size() == 2) line.push_back({measure_at_[0], measure_at_[1]});
  pick_.Set(ring);
  measure_.Set(line);
}

FieldWindow MapView::WholeRun(const review::RunModel& model) const {
  // A pass over every plant and path point: once per model state (a
  // reviewed run's never changes).
  if (&model == whole_model_ && model.messages() == whole_messages_ && model.tile_revision_sum() == whole_tiles_) {
    return whole_;
  }
  whole_model_ = &model, whole_messages_ = model.messages(), whole_tiles_ = model.tile_revision_sum();
  whole_ = WholeRunOf(model);
  return whole_;
}

FieldWindow MapView::WholeRunOf(const review::RunModel& model) const {
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

double MapView::FollowBehind(const review::RunModel& model, double vehicle_y_m) {
  if (&model != trail_model_ || model.messages() < trail_messages_) trail_.clear();  // another run, or sought back
  trail_model_ = &model, trail_messages_ = model.messages();
  if (const auto front = model.map_front_y_m()) trail_.emplace_back(vehicle_y_m, vehicle_y_m - *front);
  while (!trail_.empty() && trail_.front().first < vehicle_y_m - params_.trail_window_m) trail_.pop_front();
  double trail = -1e300;
  for (const auto& [y, lag] : trail_) trail = std::max(trail, lag);
  // The vehicle sits follow_ahead_m left of the centre at the default zoom,
  // in proportion when zoomed, unless the map trails it farther.
  const double length = follow_length_m_;
  const double ahead = params_.follow_ahead_m * length / params_.follow_length_m;
  const double behind = 0.5 * length - ahead;
  const double most = std::max(behind, (1.0 - params_.keep_ahead_fraction) * length);
  return std::clamp(trail + params_.map_in_view_fraction * length, behind, most);
}

FieldWindow MapView::PlaceCamera(const review::RunModel& model) {
  FieldWindow w;
  if (window_) {
    w = *window_;
  } else if (const auto pose = model.pose()) {
    const double start = pose->y_m - FollowBehind(model, pose->y_m);
    w = {start, start + follow_length_m_, 0.0};
  }
  view_ = w;
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
  // At least min_across_m across at the default zoom; zoomed in, less.
  const double across = params_.min_across_m * std::min(1.0, (w.y1_m - w.y0_m) / params_.follow_length_m);
  camera->SetParallelScale(std::max(0.5 * across, 0.5 * (w.y1_m - w.y0_m) / aspect));
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
