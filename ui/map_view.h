#pragma once
// The bed seen from above: map tiles, plant markers, predicted grid,
// covariance ellipses and the vehicle, in one renderer. Drawn with the
// direction of travel (field +y) to the right and the vehicle's left (field
// −x) up; the camera follows the vehicle or frames a given field window.

#include <vtkRenderer.h>

#include <array>
#include <deque>
#include <optional>
#include <utility>
#include <vector>

#include "ui/field_overlays.h"
#include "ui/map_layer.h"

namespace plantscale::ui {

enum class MapLayerId { kMap, kPlants, kGrid, kEllipses, kVehicle };

struct MapViewParams {
  double follow_length_m = 6.0;  // field length shown when following the vehicle
  double follow_ahead_m = 1.5;   // the vehicle sits this far left of the centre
  // The map trails the vehicle (the vehicle sends a tile row once its spray
  // bar has passed it, and its bed frame drifts from the pose drawn: 1-3 m
  // on the field preset). Following, the view moves the vehicle ahead so
  // that this fraction of it shows the newest map, by the most the map
  // trailed over the last trail_window_m driven (a tile row's cycle, not
  // each row's step), keeping the vehicle keep_ahead_fraction from the
  // view's right end.
  double map_in_view_fraction = 1.0 / 6.0;
  double keep_ahead_fraction = 1.0 / 8.0;
  double trail_window_m = 10.0;
  double min_across_m = 1.6;     // at least this much of the bed's width is shown
  GridOverlayParams grid;
  EllipseParams ellipses;
};

class MapView {
 public:
  explicit MapView(const MapViewParams& params = {});
  void AddTo(vtkRenderer* renderer);
  void Update(const review::RunModel& model);
  void SetVisible(MapLayerId layer, bool visible);
  bool Visible(MapLayerId layer) const;
  // Frame `window` (free camera) or, with nullopt, follow the vehicle.
  void SetWindow(std::optional<FieldWindow> window) { window_ = window; }
  bool following() const { return !window_; }
  // Closer by `factor` (< 1: farther) about along-bed `about_y_m` (nullopt:
  // the view's centre); following, the followed length changes instead.
  void Zoom(double factor, std::optional<double> about_y_m = std::nullopt);
  // Moves the view by field metres (along the bed, across it); following
  // stops there (the camera stays where it was put).
  void Pan(double along_m, double across_m);
  // The field window last framed, and its metres per screen pixel.
  const FieldWindow& view() const { return view_; }
  double metres_per_pixel() const;
  // The picked plant ringed (nullopt: none) and the measure tool's points
  // (one: its first click, two: the line between them).
  void SetMarks(std::optional<Eigen::Vector2d> pick, std::vector<Eigen::Vector2d> measure);
  // The whole run: tiles, plants and path.
  FieldWindow WholeRun(const review::RunModel& model) const;
  CovarianceEllipses& ellipses() { return ellipses_; }
  const CovarianceEllipses& ellipses() const { return ellipses_; }
  const MapLayer& map_layer() const { return map_; }
  // Field point under display pixel (x, y) (VTK display coordinates, y up).
  Eigen::Vector2d FieldAtDisplay(double x, double y) const;
  // Display pixel (VTK, y up) of a field point.
  Eigen::Vector2d DisplayAtField(const Eigen::Vector2d& field) const;

 private:
  FieldWindow PlaceCamera(const review::RunModel& model);
  // How far behind the vehicle the followed view starts.
  double FollowBehind(const review::RunModel& model, double vehicle_y_m);
  FieldWindow WholeRunOf(const review::RunModel& model) const;
  void DrawMarks();

  MapViewParams params_;
  vtkRenderer* renderer_ = nullptr;
  MapLayer map_;
  PlantMarkers plants_;
  GridOverlay grid_;
  CovarianceEllipses ellipses_;
  VehicleMarker vehicle_;
  LineLayer pick_, measure_;
  std::optional<Eigen::Vector2d> pick_at_;
  std::vector<Eigen::Vector2d> measure_at_;
  double marks_mpp_ = -1.0;  // metres per pixel the marks were drawn for (< 0: redraw)
  double follow_length_m_;
  // How far the map's newest row trailed the vehicle (vehicle y, lag), the
  // last trail_window_m; and the model state they are of.
  std::deque<std::pair<double, double>> trail_;
  const review::RunModel* trail_model_ = nullptr;
  int64_t trail_messages_ = -1;
  std::optional<FieldWindow> window_;
  FieldWindow view_;
  mutable const review::RunModel* whole_model_ = nullptr;  // WholeRun's cache: the model state it was for
  mutable int64_t whole_messages_ = -1;
  mutable int whole_tiles_ = -1;
  mutable FieldWindow whole_;
  std::array<double, 4> placed_{};  // y0, y1, x centre and aspect the camera was placed for
  bool visible_[5] = {true, true, true, true, true};
};

}  // namespace plantscale::ui
