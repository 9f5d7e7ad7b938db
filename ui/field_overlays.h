#pragma once
// Layers drawn over the map in field metres: the predicted grid (row lines
// and plant lines from the grid state and the vehicle pose), covariance
// ellipses (vehicle pose and plant positions at a settable confidence), plant
// markers coloured by class, and the vehicle with its path.

#include <Eigen/Core>
#include <optional>

#include "review/run_model.h"
#include "ui/poly.h"

namespace plantscale::ui {

// A field-frame window: along-bed y range and across-bed x centre.
struct FieldWindow {
  double y0_m = 0.0, y1_m = 6.0;
  double x_centre_m = 0.0;
};

// Along-bed range a layer was built for: rebuilt when the view leaves it.
struct BuiltRange {
  double y0_m = 1.0, y1_m = -1.0;  // empty
  bool Covers(const FieldWindow& w) const { return y0_m <= w.y0_m && w.y1_m <= y1_m; }
  static BuiltRange Around(const FieldWindow& w, double margin_m) {
    return {w.y0_m - margin_m, w.y1_m + margin_m};
  }
};

// The model state a layer was last built from, so that a layer touches its
// VTK data (and the window redraws its viewport) only when the model changed.
class ModelStamp {
 public:
  // True when `model` differs from the last call's (another model, or new messages).
  bool Changed(const review::RunModel& model) {
    if (&model == model_ && model.messages() == messages_) return false;
    model_ = &model, messages_ = model.messages();
    return true;
  }
  void Reset() { model_ = nullptr; }

 private:
  const review::RunModel* model_ = nullptr;
  int64_t messages_ = -1;
};

struct GridOverlayParams {
  int rows_each_side = 1;    // rows n = −k..k drawn
  int lines_behind = 3;      // plant lines drawn behind line 0
  int lines_ahead = 10;      // and ahead of it
};

// Vehicle-frame point → field frame (inverse of sim::FieldToVehicle):
// f = p + R(ψ) v with R = [cos ψ, −sin ψ; sin ψ, cos ψ].
Eigen::Vector2d VehicleToField(const telemetry::Pose& pose, const Eigen::Vector2d& v);
// Predicted row lines (rows −k..k) and plant lines, as field-frame segments.
std::vector<Polyline> GridRowLines(const telemetry::GridEstimate& grid, const telemetry::Pose& pose,
                                   const GridOverlayParams& params);
std::vector<Polyline> GridPlantLines(const telemetry::GridEstimate& grid,
                                     const telemetry::Pose& pose, const GridOverlayParams& params);

class GridOverlay {
 public:
  explicit GridOverlay(const GridOverlayParams& params = {});
  void AddTo(vtkRenderer* renderer);
  void Update(const review::RunModel& model);
  void SetVisible(bool visible);

 private:
  GridOverlayParams params_;
  LineLayer rows_, lines_;
  ModelStamp built_;
};

// The vehicle's position covariance in the field frame: its pose's, else
// (a vehicle that publishes its pose without one) the tracker's covariance
// of offset and forward position turned by the heading; nullopt without either.
std::optional<Eigen::Matrix2d> VehicleCovariance(const review::RunModel& model, const telemetry::Pose& pose);

struct EllipseParams {
  double confidence = 0.95;  // probability inside each ellipse
  // Drawn this many times their size about their centres: a plant's 3 mm sd
  // is a 7 mm ellipse at 95 %, under its own marker at a map's scale.
  double magnification = 1.0;
  double min_plant_age_s = 0.0;
  int max_plants = 4000;     // newest plants drawn
  double max_view_m = 60.0;  // no plant ellipses in a longer view (a few pixels each there)
};

class CovarianceEllipses {
 public:
  // Throws std::invalid_argument when confidence is outside (0, 1).
  explicit CovarianceEllipses(const EllipseParams& params = {});
  void AddTo(vtkRenderer* renderer);
  // Plants are drawn near `view` only (the whole run in a report).
  void Update(const review::RunModel& model, const FieldWindow& view);
  void SetConfidence(double confidence);
  // Throws std::invalid_argument unless magnification > 0.
  void SetMagnification(double magnification);
  const EllipseParams& params() const { return params_; }
  void SetVisible(bool visible);
  // What the last update drew: the vehicle's ellipse, plants' ellipses.
  bool drew_vehicle() const { return drew_vehicle_; }
  bool drew_plants() const { return drew_plants_; }

 private:
  double DrawnK2() const { return k2_ * params_.magnification * params_.magnification; }
  EllipseParams params_;
  double k2_;
  LineLayer vehicle_, plants_;
  int64_t seen_plants_ = -1;
  int64_t seen_messages_ = -1;
  BuiltRange built_;
  bool drew_vehicle_ = false, drew_plants_ = false;
};

class PlantMarkers {
 public:
  void AddTo(vtkRenderer* renderer) { points_.AddTo(renderer); }
  void Update(const review::RunModel& model, const FieldWindow& view);
  void SetVisible(bool visible) { points_.SetVisible(visible); }

 private:
  PointLayer points_{5.0, 0.02};
  int64_t seen_messages_ = -1;
  BuiltRange built_;
};

class VehicleMarker {
 public:
  VehicleMarker();
  void AddTo(vtkRenderer* renderer);
  void Update(const review::RunModel& model);
  void SetVisible(bool visible);

 private:
  LineLayer body_, path_;
  ModelStamp built_;
};

}  // namespace plantscale::ui
