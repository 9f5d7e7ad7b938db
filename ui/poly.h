#pragma once
// Small helpers for line and point layers: a poly-data actor with one colour
// whose geometry is replaced wholesale on update.

#include <vtkActor.h>
#include <vtkNew.h>
#include <vtkPolyData.h>
#include <vtkRenderer.h>

#include <Eigen/Core>
#include <vector>

#include "ui/canvas.h"

namespace plantscale::ui {

using Polyline = std::vector<Eigen::Vector2d>;

// Points of the `k2` Mahalanobis ellipse of `covariance` around `centre`
// (closed: the first point repeated), `segments` straight pieces.
Polyline EllipseOutline(const Eigen::Vector2d& centre, const Eigen::Matrix2d& covariance, double k2,
                        int segments = 48);

class LineLayer {
 public:
  LineLayer(Rgb colour, double width_px, double z = 0.0);
  void AddTo(vtkRenderer* renderer) { renderer->AddActor(actor_); }
  void Set(const std::vector<Polyline>& lines);
  void SetVisible(bool visible) { actor_->SetVisibility(visible); }
  vtkActor* actor() { return actor_; }

 private:
  double z_;
  vtkNew<vtkPolyData> data_;
  vtkNew<vtkActor> actor_;
};

// Points drawn as squares of `size_px`, each with its own colour.
class PointLayer {
 public:
  PointLayer(double size_px, double z = 0.0);
  void AddTo(vtkRenderer* renderer) { renderer->AddActor(actor_); }
  void Set(const std::vector<Eigen::Vector2d>& points, const std::vector<Rgb>& colours);
  void SetVisible(bool visible) { actor_->SetVisibility(visible); }

 private:
  double z_;
  vtkNew<vtkPolyData> data_;
  vtkNew<vtkActor> actor_;
};

}  // namespace plantscale::ui
