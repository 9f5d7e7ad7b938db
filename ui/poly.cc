#include "ui/poly.h"

#include <vtkCellArray.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyDataMapper.h>
#include <vtkProperty.h>
#include <vtkUnsignedCharArray.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <numbers>

namespace plantscale::ui {

Polyline EllipseOutline(const Eigen::Vector2d& centre, const Eigen::Matrix2d& covariance, double k2,
                        int segments) {
  // x = c + V · diag(√(k² λ)) · (cos t, sin t): the k² contour of N(c, Σ), Σ = V Λ Vᵀ.
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(0.5 * (covariance + covariance.transpose()));
  const Eigen::Vector2d radii = (k2 * eig.eigenvalues().cwiseMax(0.0)).cwiseSqrt();
  const Eigen::Matrix2d axes = eig.eigenvectors() * radii.asDiagonal();
  Polyline out;
  for (int i = 0; i <= segments; ++i) {
    const double t = 2.0 * std::numbers::pi * i / segments;
    out.push_back(centre + axes * Eigen::Vector2d(std::cos(t), std::sin(t)));
  }
  return out;
}

LineLayer::LineLayer(Rgb colour, double width_px, double z) : z_(z) {
  vtkNew<vtkPolyDataMapper> mapper;
  mapper->SetInputData(data_);
  actor_->SetMapper(mapper);
  actor_->GetProperty()->SetColor(colour.r, colour.g, colour.b);
  actor_->GetProperty()->SetLineWidth(static_cast<float>(width_px));
  actor_->GetProperty()->LightingOff();
}

void LineLayer::Set(const std::vector<Polyline>& lines) {
  vtkNew<vtkPoints> points;
  vtkNew<vtkCellArray> cells;
  for (const Polyline& line : lines) {
    if (line.size() < 2) continue;
    cells->InsertNextCell(static_cast<vtkIdType>(line.size()));
    for (const Eigen::Vector2d& p : line) {
      cells->InsertCellPoint(points->InsertNextPoint(p.x(), p.y(), z_));
    }
  }
  data_->Initialize();
  data_->SetPoints(points);
  data_->SetLines(cells);
  data_->Modified();
}

PointLayer::PointLayer(double size_px, double z) : z_(z) {
  vtkNew<vtkPolyDataMapper> mapper;
  mapper->SetInputData(data_);
  mapper->SetScalarModeToUsePointData();
  actor_->SetMapper(mapper);
  actor_->GetProperty()->SetPointSize(static_cast<float>(size_px));
  actor_->GetProperty()->LightingOff();
}

void PointLayer::Set(const std::vector<Eigen::Vector2d>& points_in, const std::vector<Rgb>& colours) {
  vtkNew<vtkPoints> points;
  vtkNew<vtkCellArray> verts;
  vtkNew<vtkUnsignedCharArray> rgb;
  rgb->SetNumberOfComponents(3);
  for (size_t i = 0; i < points_in.size(); ++i) {
    verts->InsertNextCell(1);
    verts->InsertCellPoint(points->InsertNextPoint(points_in[i].x(), points_in[i].y(), z_));
    const Rgb c = i < colours.size() ? colours[i] : Rgb{1, 1, 1};
    const auto byte = [](double v) { return static_cast<unsigned char>(std::clamp(v, 0.0, 1.0) * 255.0); };
    rgb->InsertNextTuple3(byte(c.r), byte(c.g), byte(c.b));
  }
  data_->Initialize();
  data_->SetPoints(points);
  data_->SetVerts(verts);
  data_->GetPointData()->SetScalars(rgb);
  data_->Modified();
}

}  // namespace plantscale::ui
